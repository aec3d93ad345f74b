"""The tracker's configuration: one dataclass per component composed into :class:`TrackerConfig`, with YAML/JSON I/O.

The same dataclasses drive the CLI (tyro), the viewer's sliders (field
``metadata`` min/max/step/unit) and config files. Files hold a nested mapping
mirroring the dataclasses; missing keys keep their defaults, unknown keys are an
error (a typo must not silently do nothing).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from pathlib import Path

from evpose.frontend.distance_field import DistanceFieldConfig
from evpose.frontend.noise_filter import NoiseFilterConfig
from evpose.frontend.time_surface import TimeSurfaceConfig
from evpose.fusion.config import FusionConfig
from evpose.fusion.ego_motion import EgoMotionConfig
from evpose.fusion.polarity_config import PolarityFilterConfig
from evpose.io.config_file import config_from_dict, config_to_dict, read_config, write_config  # noqa: F401 - re-exported
from evpose.tracker.edge_offsets import EdgeOffsetConfig
from evpose.tracker.event_registration_config import EventRegistrationConfig
from evpose.tracker.map_refinement import MapRefinementConfig
from evpose.tracker.motion_filter_config import MotionFilterConfig
from evpose.tracker.reacquisition import ReacquisitionConfig
from evpose.tracker.registration_config import RegistrationConfig
from evpose.tracker.visible_map import VisibleMapConfig
from evpose.tracker.event_gaps import DEFAULT_MAX_EVENT_GAP_MS, RestartGateConfig


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
    """Extrapolate the twist of the recent poses; each registration becomes the pose as it is."""
    CONSTANT_POSE = "constant_pose"
    """The next pose is the last one."""
    KALMAN = "kalman"
    """Constant-velocity Kalman filter fusing each registration with its covariance (``motion_filter``)."""


@dataclass
class TrackerConfig:
    """Everything the tracking engine needs besides the map and the calibration."""

    mode: TrackerMode = TrackerMode.FULL
    """Which parts of EV-Pose run."""
    rate_hz: float = field(default=200.0, metadata={"min": 10.0, "max": 1000.0, "step": 10.0, "unit": "Hz"})
    """Pose updates per second of recording time, Hz."""
    motion_model: MotionModel = MotionModel.KALMAN
    """Prediction of the next pose (used for culling and as the registration's start)."""
    velocity_window_ms: float = field(default=0.0, metadata={"min": 0.0, "max": 200.0, "step": 1.0, "unit": "ms"})
    """The constant-velocity model fits its twist to the poses of this last stretch (0 = last two poses), milliseconds.

    A two-pose velocity turns the registration noise of each update into velocity
    noise that the prediction, the lag compensation and the pose prior inherit."""
    initial_velocity_from_ground_truth: bool = True
    """When starting from ground truth, also seed the motion model with the ground-truth velocity at the start."""
    warmup_ms: float = field(default=30.0, metadata={"min": 0.0, "max": 1000.0, "step": 1.0, "unit": "ms"})
    """Events this long before the start time are fed to the front end before the first update, milliseconds.
    (120, a full time surface at the first update: 240x180 seeds 0-7 7.89 mm against 7.325, from 90 ms later.)"""
    field_margin_px: int = field(default=24, metadata={"min": 0, "max": 200, "step": 1, "unit": "px"})
    """The TDF is built only in the box around the projected visible map, padded by this, pixels."""
    max_event_gap_ms: float = field(default=DEFAULT_MAX_EVENT_GAP_MS, metadata={"min": 50.0, "max": 3.6e6, "step": 50.0, "unit": "ms"})
    """A stretch without events (in the fused modes, or without IMU samples) longer than this ends the track: a
    TrackingSession reports one lost update for the whole gap (not one per empty update: a 1 h pause was 720k updates)
    and restarts the tracker after it as at the start (the ground-truth pose when it started from ground truth, else
    the last estimate, in ``full`` carried on at its last velocity (``restart_gate.carry_velocity``), its updates
    written once ``restart_gate`` passes, or with
    ``reacquisition.enabled`` where its search finds the camera),
    milliseconds. Shorter outages are bridged as before (the fused modes propagate
    the IMU). See ``evpose.tracker.event_gaps``."""
    snapshot_every: int = field(default=50, metadata={"min": 1, "max": 10000, "step": 1, "unit": "steps"})
    """A TrackingSession keeps a full-state snapshot every this many steps (for seeking), steps."""
    noise_filter: NoiseFilterConfig = field(default_factory=NoiseFilterConfig)
    time_surface: TimeSurfaceConfig = field(default_factory=TimeSurfaceConfig)
    distance_field: DistanceFieldConfig = field(default_factory=DistanceFieldConfig)
    visible_map: VisibleMapConfig = field(default_factory=VisibleMapConfig)
    registration: RegistrationConfig = field(default_factory=RegistrationConfig)
    motion_filter: MotionFilterConfig = field(default_factory=MotionFilterConfig)
    """Constant-velocity Kalman filter of ``motion_model: kalman`` (``stpe`` mode)."""
    map_refinement: MapRefinementConfig = field(default_factory=MapRefinementConfig)
    """Online refinement of the map's painted edges (``stpe`` mode)."""
    edge_offsets: EdgeOffsetConfig = field(default_factory=EdgeOffsetConfig)
    """Gauge-free online offsets of every registered point along its edge normal (``stpe`` on coarse sensors)."""
    event_registration: EventRegistrationConfig = field(default_factory=EventRegistrationConfig)
    """Refinement of the fused modes' registrations on the step's events at their own timestamps (``full``)."""
    polarity: PolarityFilterConfig = field(default_factory=PolarityFilterConfig)
    """Motion-instructed polarity filter (``stpe+filter`` and ``full``)."""
    fusion: FusionConfig = field(default_factory=FusionConfig)
    """IMU fusion (``full``; ``stpe+filter`` uses it only for the motion the polarity filter needs)."""
    ego_motion: EgoMotionConfig = field(default_factory=EgoMotionConfig)
    """Ego-motion infrastructure extraction (``full`` only): drop events the IMU-predicted motion does not explain."""
    reacquisition: ReacquisitionConfig = field(default_factory=ReacquisitionConfig)
    """The search for the pose when the tracker restarts without knowing it (after an event gap without ground
    truth; see ``evpose.tracker.reacquisition``)."""
    restart_gate: RestartGateConfig = field(default_factory=RestartGateConfig)
    """Whether the updates after a restart from the last estimate are written before the map's chance-level evidence
    is back (see ``evpose.tracker.event_gaps``)."""


def load_config(path: str | Path) -> TrackerConfig:
    """Read a TrackerConfig from ``.yaml``/``.yml``/``.json``; missing keys keep their defaults."""
    return read_config(TrackerConfig, path)


def save_config(cfg: TrackerConfig, path: str | Path) -> None:
    """Write ``cfg`` atomically as JSON (``.json``) or YAML (anything else)."""
    write_config(cfg, path)
