"""A recording: events + IMU + optional ground truth + calibration + metadata."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evpose.core.camera import MAX_SENSOR_PX, CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory
from evpose.errors import InputError


def metadata_sensor_size(metadata: dict, source: str | Path | None) -> tuple[int, int] | None:
    """(width, height) stated by a recording's metadata, or None; checked, since a file's metadata is free-form JSON
    (a width of "big" ended in int()'s ValueError traceback)."""
    if "width" not in metadata or "height" not in metadata:
        return None
    w, h = metadata["width"], metadata["height"]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and float(v).is_integer() and 1 <= v <= MAX_SENSOR_PX for v in (w, h)):
        raise InputError(source, f"metadata width/height {w!r} x {h!r} is not a sensor size (1..{MAX_SENSOR_PX} pixels)")
    return int(w), int(h)


@dataclass
class Recording:
    """Everything one sensor rig captured in one session, in memory.

    Times are int64 microseconds on the camera clock; ``calibration.time_offset_us``
    converts IMU times. ``metadata`` holds free-form provenance (simulator
    scenario, seed, source format...), JSON-serialisable.
    """

    events: EventArray
    imu: ImuSamples | None = None
    ground_truth: Trajectory | None = None
    calibration: CameraCalibration | None = None
    metadata: dict = field(default_factory=dict)
    source: Path | None = None
    """File or folder this recording was read from, if any."""

    @property
    def sensor_size(self) -> tuple[int, int] | None:
        """(width, height) from the calibration, else from metadata, else None."""
        if self.calibration is not None:
            return self.calibration.width, self.calibration.height
        return metadata_sensor_size(self.metadata, self.source)

    @property
    def t_start_us(self) -> int:
        return int(self.events.t[0]) if len(self.events) else 0

    @property
    def t_end_us(self) -> int:
        return int(self.events.t[-1]) if len(self.events) else 0

    def validate(self) -> None:
        """Check every stream; raise InputError naming the first bad record."""
        src = str(self.source) if self.source else None
        size = self.sensor_size
        self.events.validate(*(size if size else (None, None)), source=src)
        if self.imu is not None:
            self.imu.validate(source=src)
        if self.ground_truth is not None:
            self.ground_truth.validate(source=src)

    def summary(self) -> dict:
        """The figures ``evpose info`` prints."""
        n = len(self.events)
        dur = (self.t_end_us - self.t_start_us) / 1e6 if n else 0.0
        out = {
            "source": str(self.source) if self.source else None,
            "sensor_size": list(self.sensor_size) if self.sensor_size else None,
            "duration_s": dur,
            "events": n,
            "event_rate_hz": n / dur if dur > 0 else 0.0,
            "positive_share": float(np.mean(self.events.p > 0)) if n else 0.0,
            "imu_samples": len(self.imu) if self.imu is not None else 0,
            "imu_rate_hz": self.imu.rate_hz if self.imu is not None else 0.0,
            "ground_truth_poses": len(self.ground_truth) if self.ground_truth is not None else 0,
            "calibration": self.calibration.to_dict() if self.calibration is not None else None,
        }
        return out
