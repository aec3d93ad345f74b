"""What the viewer shows for one engine step, independent of which engine produced it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.events import EventArray


@dataclass
class Frame:
    """One step as displayed: images, per-point products and the scalar figures the plots use."""

    index: int
    """Step number, 0-based, in the order a headless run produces them."""
    t_us: int
    """Time of the step, microseconds (camera clock)."""
    ts_positive: np.ndarray
    """SP-TS of ON events, float32 (H, W) in [0, 1]."""
    ts_negative: np.ndarray
    """SP-TS of OFF events, float32 (H, W) in [0, 1]."""
    tdf: np.ndarray
    """Distance field, float32 (H, W); ~0 on the newest edges."""
    events_kept: EventArray
    """Events of this step that passed the filters."""
    events_removed: EventArray
    """Events of this step the filters removed."""
    pose: np.ndarray | None = None
    """Best estimate ``T_world_cam`` (4, 4), or None when nothing is tracked."""
    registration_pose: np.ndarray | None = None
    """Raw registration pose (4, 4) before fusion, if any."""
    status: str = "events only"
    """Tracker status value (``TrackStatus``) or 'events only'."""
    reason: str = ""
    """Why the status is not OK, in plain words."""
    point_index: np.ndarray | None = None
    """Map indices of the points registration used, int64 (M,)."""
    visible_index: np.ndarray | None = None
    """Map indices of the points that survived culling, int64 (V,)."""
    projected_uv: np.ndarray | None = None
    """Projections of the used points, float32 (M, 2), pixels."""
    residuals: np.ndarray | None = None
    """Residual per used point, float32 (M,)."""
    weights: np.ndarray | None = None
    """Robust weight per used point, float32 (M,)."""
    predicted_polarity: np.ndarray | None = None
    """+1/-1 predicted polarity per used point, 0 in the buffer zone, int8 (M,)."""
    imu_poses: np.ndarray | None = None
    """IMU-rate poses since the previous step, (K, 4, 4)."""
    timings_ms: dict[str, float] = field(default_factory=dict)
    """Wall time per module, milliseconds."""
    counts: dict[str, int] = field(default_factory=dict)
    """events_in, events_kept, points_visible, points_used, inliers ..."""


@dataclass
class StepSummary:
    """The small per-step record kept for the whole run (plots, trajectory, export)."""

    index: int
    t_us: int
    pose: np.ndarray | None
    registration_pose: np.ndarray | None
    status: str
    timings_ms: dict[str, float]
    counts: dict[str, int]

    @classmethod
    def of(cls, frame: Frame) -> "StepSummary":
        return cls(frame.index, frame.t_us, frame.pose, frame.registration_pose, frame.status, dict(frame.timings_ms), dict(frame.counts))
