"""The tracker's configuration: one dataclass per component composed into :class:`TrackerConfig`, with YAML/JSON I/O.

The same dataclasses drive the CLI (tyro), the viewer's sliders (field
``metadata`` min/max/step/unit) and config files. Files hold a nested mapping
mirroring the dataclasses; missing keys keep their defaults, unknown keys are an
error (a typo must not silently do nothing).
"""

from __future__ import annotations

import dataclasses
import enum
import json
import typing
from dataclasses import dataclass, field
from pathlib import Path

from evpose.errors import InputError
from evpose.frontend.distance_field import DistanceFieldConfig
from evpose.frontend.noise_filter import NoiseFilterConfig
from evpose.frontend.time_surface import TimeSurfaceConfig
from evpose.fusion.config import FusionConfig
from evpose.fusion.ego_motion import EgoMotionConfig
from evpose.fusion.polarity import PolarityFilterConfig
from evpose.io.atomic import atomic_path
from evpose.tracker.registration import RegistrationConfig
from evpose.tracker.visible_map import VisibleMapConfig


class TrackerMode(str, enum.Enum):
    """Which parts of EV-Pose run."""

    STPE = "stpe"
    """Event-map registration alone (section IV), constant-velocity prediction."""
    STPE_FILTER = "stpe+filter"
    """STPE with the motion-instructed polarity filter (section V-A)."""
    FULL = "full"
    """STPE, polarity filter and factor-graph fusion with the IMU (section V)."""


class MotionModel(str, enum.Enum):
    """How the tracker predicts the next pose in ``stpe`` mode."""

    CONSTANT_VELOCITY = "constant_velocity"
    CONSTANT_POSE = "constant_pose"


@dataclass
class TrackerConfig:
    """Everything the tracking engine needs besides the map and the calibration."""

    mode: TrackerMode = TrackerMode.FULL
    """Which parts of EV-Pose run."""
    rate_hz: float = field(default=200.0, metadata={"min": 10.0, "max": 1000.0, "step": 10.0, "unit": "Hz"})
    """Pose updates per second of recording time, Hz."""
    motion_model: MotionModel = MotionModel.CONSTANT_VELOCITY
    """Prediction of the next pose (used for culling and as the registration's start)."""
    initial_velocity_from_ground_truth: bool = True
    """When starting from ground truth, also seed the motion model with the ground-truth velocity at the start."""
    warmup_ms: float = field(default=30.0, metadata={"min": 0.0, "max": 1000.0, "step": 1.0, "unit": "ms"})
    """Events this long before the start time are fed to the front end before the first update, milliseconds."""
    field_margin_px: int = field(default=24, metadata={"min": 0, "max": 200, "step": 1, "unit": "px"})
    """The TDF is built only in the box around the projected visible map, padded by this, pixels."""
    snapshot_every: int = field(default=50, metadata={"min": 1, "max": 10000, "step": 1, "unit": "steps"})
    """A TrackingSession keeps a full-state snapshot every this many steps (for seeking), steps."""
    noise_filter: NoiseFilterConfig = field(default_factory=NoiseFilterConfig)
    time_surface: TimeSurfaceConfig = field(default_factory=TimeSurfaceConfig)
    distance_field: DistanceFieldConfig = field(default_factory=DistanceFieldConfig)
    visible_map: VisibleMapConfig = field(default_factory=VisibleMapConfig)
    registration: RegistrationConfig = field(default_factory=RegistrationConfig)
    polarity: PolarityFilterConfig = field(default_factory=PolarityFilterConfig)
    """Motion-instructed polarity filter (``stpe+filter`` and ``full``)."""
    fusion: FusionConfig = field(default_factory=FusionConfig)
    """IMU fusion (``full``; ``stpe+filter`` uses it only for the motion the polarity filter needs)."""
    ego_motion: EgoMotionConfig = field(default_factory=lambda: EgoMotionConfig(enabled=False))
    """Ego-motion infrastructure extraction (``full`` only): drop events the IMU-predicted motion does not explain."""


def config_to_dict(cfg) -> dict:
    """Nested plain dict (enums as their values) of a config dataclass."""
    out = {}
    for f in dataclasses.fields(cfg):
        v = getattr(cfg, f.name)
        if dataclasses.is_dataclass(v):
            v = config_to_dict(v)
        elif isinstance(v, enum.Enum):
            v = v.value
        out[f.name] = v
    return out


def config_from_dict(cls, data: dict, source: str | None = None, prefix: str = ""):
    """Build dataclass ``cls`` from a nested dict; unknown keys and wrong types raise :class:`InputError`."""
    if not isinstance(data, dict):
        raise InputError(source, f"expected a mapping, got {type(data).__name__}", prefix.rstrip(".") or None)
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise InputError(source, f"unknown setting (known: {', '.join(sorted(names))})", prefix + str(unknown[0]))
    kwargs = {}
    for name, raw in data.items():
        typ = hints[name]
        key = prefix + name
        if dataclasses.is_dataclass(typ):
            kwargs[name] = config_from_dict(typ, raw, source, key + ".")
            continue
        try:
            if isinstance(typ, type) and issubclass(typ, enum.Enum):
                kwargs[name] = typ(raw)
            elif typ is bool:
                if not isinstance(raw, bool):
                    raise ValueError(f"expected true/false, got {raw!r}")
                kwargs[name] = raw
            elif typ is int:
                if isinstance(raw, bool) or float(raw) != int(float(raw)):
                    raise ValueError(f"expected an integer, got {raw!r}")
                kwargs[name] = int(float(raw))
            elif typ is float:
                if isinstance(raw, bool):
                    raise ValueError(f"expected a number, got {raw!r}")
                kwargs[name] = float(raw)
            else:
                kwargs[name] = raw
        except (TypeError, ValueError) as exc:
            raise InputError(source, str(exc), key) from None
    return cls(**kwargs)


def load_config(path: str | Path) -> TrackerConfig:
    """Read a TrackerConfig from ``.yaml``/``.yml``/``.json``; missing keys keep their defaults."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(path, f"cannot read the config file ({exc.strerror})") from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            import yaml

            data = yaml.safe_load(text)
    except Exception as exc:  # noqa: BLE001 - any parser error is bad input
        raise InputError(path, f"not valid {'JSON' if path.suffix.lower() == '.json' else 'YAML'} ({str(exc).splitlines()[0]})") from None
    return config_from_dict(TrackerConfig, data or {}, str(path))


def save_config(cfg: TrackerConfig, path: str | Path) -> None:
    """Write ``cfg`` atomically as JSON (``.json``) or YAML (anything else)."""
    path = Path(path)
    data = config_to_dict(cfg)
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".json":
            tmp.write_text(json.dumps(data, indent=2) + "\n")
        else:
            import yaml

            tmp.write_text(yaml.safe_dump(data, sort_keys=False))
