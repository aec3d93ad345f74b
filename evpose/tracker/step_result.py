"""What one tracker step returns; the contract between the engine, the CLI, the benchmarks and the viewer."""

from __future__ import annotations

import enum
import time
from dataclasses import dataclass, field

import numpy as np

from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory


class TrackStatus(str, enum.Enum):
    """Health of the estimate after a step."""

    OK = "ok"
    """Registration succeeded (and was fused, in fused modes)."""
    DEGRADED = "degraded"
    """Registration failed this step; the pose is IMU-propagated (fused modes only)."""
    LOST = "lost"
    """No trustworthy pose: registration failed and nothing can bridge the gap."""
    NOT_INITIALISED = "not_initialised"
    """No initial pose yet."""


@dataclass
class StepDebug:
    """Per-step images and per-point products, computed only when a step is asked for them."""

    ts_positive: np.ndarray
    """SP-TS of ON events at the step time, float32 (H, W) in [0, 1]."""
    ts_negative: np.ndarray
    """SP-TS of OFF events, float32 (H, W) in [0, 1]."""
    tdf: np.ndarray
    """Distance field registration used (combined polarity, after blur), float32 (H, W)."""
    visible_index: np.ndarray
    """Indices into the map of the points that survived FoV/occlusion culling, int64 (V,)."""
    point_index: np.ndarray
    """Indices into the map of the points registration used, int64 (M,)."""
    projected_uv: np.ndarray
    """Their projections at the final pose, float32 (M, 2), ideal-pinhole pixels."""
    residuals: np.ndarray
    """Final residual per used point, float32 (M,)."""
    weights: np.ndarray
    """Final robust weight per used point, float32 (M,)."""
    predicted_polarity: np.ndarray
    """Per used point: +1/-1 predicted polarity, 0 inside the buffer zone (both used), int8 (M,)."""
    events_kept: EventArray
    """Events of this step that passed all filters."""
    events_removed: EventArray
    """Events of this step removed by the noise, polarity or ego-motion filters."""
    extra: dict = field(default_factory=dict)
    """Stage-specific extras (e.g. per-polarity TDFs), name -> array."""


@dataclass
class StepResult:
    """The outcome of ``Tracker.step``: one pose update."""

    t_us: int
    """Time of the estimate, microseconds (camera clock)."""
    pose: np.ndarray
    """Best estimate ``T_world_cam`` (4, 4): fused where fusion runs, else the registration."""
    status: TrackStatus
    reason: str = ""
    """Why the status is not OK, in plain words."""
    registration_pose: np.ndarray | None = None
    """Raw registration result ``T_world_cam`` before fusion, if registration ran."""
    covariance: np.ndarray | None = None
    """(6, 6) covariance of ``pose`` in gtsam's Pose3 tangent order (rotation, translation), body frame."""
    velocity: np.ndarray | None = None
    """World-frame camera velocity (3,), m/s, where fusion estimates it."""
    timings_ms: dict[str, float] = field(default_factory=dict)
    """Wall time per module for this step, milliseconds; key 'total' is the whole step."""
    counts: dict[str, int] = field(default_factory=dict)
    """events_in, events_kept, points_visible, points_used, inliers, iterations ..."""
    imu_poses: Trajectory | None = None
    """IMU-rate propagated poses between the previous step and this one (fused modes)."""
    debug: StepDebug | None = None


def step_debug(time_surface, distance_field, until, events, keep, visible, used, reg, polarity) -> StepDebug:
    """The debug products of one tracker step: its SP-TS and TDF images, the per-point registration results and the
    events the filters kept and removed (``reg`` None when registration did not run)."""
    m = used.size
    extra = {}
    for p in (1, -1):
        slot = 1 if p > 0 else 2
        if slot in distance_field.slots_ready:
            extra[f"tdf_{'positive' if p > 0 else 'negative'}"] = distance_field.image(p)
    return StepDebug(
        ts_positive=time_surface.image(until, 1),
        ts_negative=time_surface.image(until, -1),
        tdf=distance_field.image(0),
        visible_index=visible.astype(np.int64),
        point_index=used.astype(np.int64),
        projected_uv=reg.uv if reg is not None else np.full((m, 2), np.nan, np.float32),
        residuals=reg.residuals if reg is not None else np.ones(m, np.float32),
        weights=reg.weights if reg is not None else np.zeros(m, np.float32),
        predicted_polarity=np.zeros(m, np.int8) if polarity is None else np.asarray(polarity, np.int8),
        events_kept=events[keep],
        events_removed=events[~keep],
        extra=extra,
    )


def elapsed_ms(t0: float) -> float:
    """Milliseconds since ``t0`` (a ``time.perf_counter()`` reading), as :attr:`StepResult.timings_ms` holds them."""
    return (time.perf_counter() - t0) * 1e3
