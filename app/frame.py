"""What the viewer shows for one engine step, independent of which engine produced it."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from evpose.core.events import EventArray


@dataclass
class SlamView:
    """What a SLAM step adds to a frame (``evpose.slam.SlamStepResult``, in the viewer's terms)."""

    tiny_frame: np.ndarray | None
    """Last tiny frame, float32 (H, W)."""
    mci: np.ndarray | None
    """Selected motion-compensated image, float32 (H, W), when one was made in this step."""
    hypothesis: str
    """Name of the selected MCI hypothesis ("H1".."H5"), "" without an MCI."""
    hypothesis_scores: dict[str, float]
    """Score (mean local STD) of every hypothesis tried."""
    features: np.ndarray | None
    """Tracked feature positions on the MCI, (N, 2) pixels."""
    feature_has_point: np.ndarray | None
    """Whether each track carries a map point, bool (N,)."""
    keyframe: bool
    """A keyframe was inserted at this step."""
    map_id: int
    """Active map of the atlas (-1 before the first)."""
    map_points: np.ndarray | None
    """Points of the active map, (M, 3) map units."""
    keyframe_poses: np.ndarray | None
    """``T_world_cam`` of the active map's keyframes, (K, 4, 4) map units."""
    mci_t_us: int | None = None
    """Time of the MCI shown (a step without a new MCI shows the last one), us."""
    atlas: list = field(default_factory=list)
    """Every map of the atlas so far with its alignment to the ground truth (``app.slam_alignment.AtlasMapView``)."""
    has_ground_truth: bool = False
    """The recording has ground truth, so the maps can be shown aligned to it."""


@dataclass
class Frame:
    """One step as displayed: images, per-point products and the scalar figures the plots use."""

    index: int
    """Step number, 0-based, in the order a headless run produces them."""
    t_us: int
    """Time of the step, microseconds (camera clock)."""
    ts_positive: np.ndarray
    """SP-TS of ON events, float32 (H, W) in [0, 1], or uint8 as displayed (``frame_cache.quantize``: value * 255)."""
    ts_negative: np.ndarray
    """SP-TS of OFF events, float32 (H, W) in [0, 1], or uint8 as displayed."""
    tdf: np.ndarray
    """Distance field, float32 (H, W), or uint8 as displayed; ~0 on the newest edges."""
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
    slam: SlamView | None = None
    """SLAM products when the SLAM engine made this frame."""
    preview: bool = False
    """Only the front end's images at this step, shown while the pose (causal: it needs every step before) is being
    computed (``Engine.preview``); never kept, never in the history."""


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


def frame_from_result(result, index: int) -> Frame:
    """Convert a tracker ``StepResult`` (with debug products) into a displayed frame."""
    d = result.debug
    imu = result.imu_poses.matrices() if result.imu_poses is not None and len(result.imu_poses) else None
    if d is None:
        empty = np.zeros((1, 1), np.float32)
        return Frame(index, int(result.t_us), empty, empty, empty, EventArray.empty(), EventArray.empty(),
                     pose=result.pose, registration_pose=result.registration_pose, status=result.status.value,
                     reason=result.reason, imu_poses=imu, timings_ms=dict(result.timings_ms), counts=dict(result.counts))
    return Frame(
        index=index, t_us=int(result.t_us), ts_positive=d.ts_positive, ts_negative=d.ts_negative, tdf=d.tdf,
        events_kept=d.events_kept, events_removed=d.events_removed, pose=result.pose,
        registration_pose=result.registration_pose, status=result.status.value, reason=result.reason,
        point_index=d.point_index, visible_index=d.visible_index, projected_uv=d.projected_uv,
        residuals=d.residuals, weights=d.weights, predicted_polarity=d.predicted_polarity, imu_poses=imu,
        timings_ms=dict(result.timings_ms), counts=dict(result.counts),
    )


def summary_from_result(result, index: int) -> StepSummary:
    return StepSummary(index, int(result.t_us), result.pose, result.registration_pose, result.status.value,
                       dict(result.timings_ms), dict(result.counts))


def imageless_frame(result, index: int, sensor_size: tuple[int, int]) -> Frame:
    """A tracker step without debug products (the update standing for a long event gap), shown with blank images of
    the sensor's size (the surfaces have faded over the gap) and its status and reason."""
    w, h = sensor_size
    blank = np.zeros((int(h), int(w)), np.uint8)  # 8-bit as kept frames are (frame_cache.compact); TDF 255: no edge
    return dataclasses.replace(frame_from_result(result, index), ts_positive=blank, ts_negative=blank,
                               tdf=np.full_like(blank, 255))
