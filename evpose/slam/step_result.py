"""What one SLAM step returns: the contract between the SLAM engine, the CLI, the benchmarks and the viewer."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np


class SlamStatus(str, enum.Enum):
    """Health of the SLAM system after a step."""

    WAITING = "waiting"
    """No new MCI in this step (collecting events, or the camera is still / untextured; see ``reason``)."""
    NOT_INITIALISED = "not_initialised"
    """An MCI was processed but no map exists yet (two-view initialisation pending)."""
    OK = "ok"
    """The MCI was tracked against the active map."""
    INERTIAL = "inertial"
    """Event-inertial C2/C3: visual tracking failed on this MCI; the pose was propagated by the IMU and the map kept."""
    COASTING = "coasting"
    """Event-only: visual tracking failed on this MCI; the pose was predicted by the map's recent motion and the map
    kept (``TrackingConfig.coast_s``)."""
    LOST = "lost"
    """Tracking failed on this MCI; the next map of the atlas will be initialised."""


class SlamFailure(str, enum.Enum):
    """Why an MCI was not tracked from the events (its status is not ``OK``)."""

    NONE = ""
    """Tracked from the events (status ``OK``), or no MCI."""
    INITIALISING = "initialising"
    """No map to track against: two-view initialisation pending."""
    STARVED = "starved"
    """Too few tracks carried map points for a pose (``TrackingConfig.min_inliers``)."""
    REJECTED = "rejected"
    """Enough tracked map points, but the pose estimate failed its checks (PnP inliers, inlier share)."""
    GAP = "gap"
    """The input paused for longer than ``TrackingConfig.lose_after_gap_s``: the map ended there (no MCI)."""


@dataclass
class SlamStepResult:
    """Outcome of ``EventSlam.step``: the state after the last MCI of the step (or the window state if none)."""

    t_us: int
    """Time of the last MCI (or of the last event seen), us."""
    status: SlamStatus
    reason: str = ""
    """Why the status is not OK, in plain words."""
    failure: SlamFailure = SlamFailure.NONE
    """The class of ``reason`` when the MCI was not tracked from the events."""
    pose: np.ndarray | None = None
    """``T_world_cam`` (4, 4) in the active map's frame and scale, when tracked."""
    map_id: int = -1
    """Index of the active map in the atlas (-1 before the first map)."""
    tiny_frame: np.ndarray | None = None
    """Last tiny frame, float32 (H, W)."""
    mci: np.ndarray | None = None
    """Selected MCI, float32 (H, W), if one was made in this step."""
    hypothesis: str = ""
    """Name of the selected MCI hypothesis ("H1".."H5")."""
    hypothesis_scores: dict[str, float] = field(default_factory=dict)
    """Mean local STD of every hypothesis tried."""
    features: np.ndarray | None = None
    """Tracked feature positions on the MCI, float32 (N, 2), ideal pixels."""
    feature_ids: np.ndarray | None = None
    """Their track ids, int64 (N,)."""
    feature_has_point: np.ndarray | None = None
    """Whether each track carries a map point, bool (N,)."""
    keyframe: bool = False
    """A keyframe was inserted at this MCI."""
    map_points: np.ndarray | None = None
    """Points of the active map, (M, 3) map units."""
    n_events_window: int = 0
    """Tiny-window size ``N_e`` after this step, events."""
    mcis: int = 0
    """MCIs processed in this step."""
    timings_ms: dict[str, float] = field(default_factory=dict)
    """Per stage for the last MCI, ms: wall 'mci', 'tracking' (KLT, pose, keyframe, local BA), 'total'; CPU 'mci_cpu', 'tracking_cpu'."""
    counts: dict[str, int] = field(default_factory=dict)
    """tracks, map_points, keyframes, events; map_tracks (tracks carrying a point of the active map when the pose was
    estimated, -1 without a map), inliers (of the accepted pose, -1 without one), blank_us (time before this MCI the
    window selection dropped for a low event rate, ``ReconstructionWindow.blank_us``, us)."""
