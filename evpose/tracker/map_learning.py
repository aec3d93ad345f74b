"""What the map points learn from an accepted update: their event offsets, edge offsets and painted edges' positions.

Called by :meth:`Tracker.step <evpose.tracker.tracker.Tracker.step>` once the update's pose and status are known; the
learned state lives in the tracker's components (``event_registration``, ``edge_offsets``, ``refiner``), which its
``snapshot()`` / ``restore()`` copy.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import gtsam
import numpy as np

from evpose.tracker.step_result import TrackStatus, elapsed_ms

if TYPE_CHECKING:
    from evpose.tracker.tracker import Tracker


def learn_map_points(tracker: Tracker, status: TrackStatus, used: np.ndarray, field_polarity: np.ndarray | None, levels: list,
                     twist: np.ndarray | None, trail: np.ndarray | None, counts: dict, timings: dict) -> None:
    """The map points' learning after the update's ``status``: event offsets, edge offsets, painted-edge refinement.

    ``used`` are the registered map points, ``levels`` the distance fields registration read (finest last), ``twist``
    and ``trail`` what it compensated the field's lag with; counts and timings (ms) are added to ``counts`` / ``timings``.
    """
    if tracker.edge_offsets is not None:
        tracker.edge_offsets.last_fit[:] = np.nan
    T_field = None
    if tracker.event_registration is not None and status is TrackStatus.OK and tracker.hold.never_lost and counts.get("events_registered"):
        # Only what an accepted update's events say, and only while the track was never lost (a wrong lock must not
        # be learned).
        counts["points_event_offset"] = tracker.event_registration.learn()
    if tracker.edge_offsets is not None and status is TrackStatus.OK and field_polarity is None and tracker.hold.never_lost:
        # As the refiner below (which takes this update's pose-like fit out of its own steps), from the pose the
        # field shows, only while the track was never lost (a wrong lock must not be learned).
        t0 = time.perf_counter()
        T_field = field_pose(tracker, twist)
        # Measured where registration read the field (the fused modes' lag floor and polarity trail).
        counts["points_offset"] = tracker.edge_offsets.update(tracker._points, used, levels[-1], T_field, tracker.K, twist,
                                                              float(tracker._registration.field_lag_ms) * 1e-3,
                                                              float(tracker._registration.lag_floor_px), trail)
        if tracker.anchored_rims is not None:
            # The rims' absolute steps, only while the points no refiner moves anchor the pose (see its module).
            counts["points_rim_refined"] = tracker.anchored_rims.update(tracker._points, used, levels[-1], T_field, tracker.K)
        timings["edge_offsets"] = elapsed_ms(t0)
    share = float(tracker.config.map_refinement.fused_refine_max_share)
    anchored = (share <= 0 or tracker.refiner is None or not tracker.components.drives_pose or not used.size
                or np.count_nonzero(tracker._painted_mask()[used]) <= share * used.size)
    if (tracker.refiner is not None and status is TrackStatus.OK and field_polarity is None and tracker.hold.never_lost
            and anchored):
        # (``map_refinement.fused_refine_max_share``: in the fused modes only while the other points anchor the pose.)
        # Registration read slot 0. A regained track may be a wrong lock the map would learn, so only a track
        # never lost since its start refines (indoor demo, stpe: refining after regains 192 -> 861 mm ATE).
        # Painted edges move towards where this update's events put them, seen from the pose the field shows.
        t0 = time.perf_counter()
        T_field = field_pose(tracker, twist) if T_field is None else T_field  # as the edge offsets read it
        gauge = None
        if tracker.edge_offsets is not None and tracker.config.edge_offsets.gauge_painted and np.isfinite(tracker.edge_offsets.last_fit).all():
            gauge = tracker.edge_offsets.last_fit
        shift = {}
        if tracker.config.map_refinement.fused_registration_shift and tracker.components.drives_pose and twist is not None:
            # Read the field where registration does (see ``MapRefinementConfig.fused_registration_shift``).
            trail_px = None if trail is None else tracker.refiner.painted_values(used, trail)
            shift = dict(twist=twist, lag_s=float(tracker._registration.field_lag_ms) * 1e-3,
                         floor_px=float(tracker._registration.lag_floor_px), trail_px=trail_px)
        counts["points_refined"] = tracker.refiner.update(tracker._points, levels[-1], T_field, tracker.K, gauge, **shift)
        timings["map_refinement"] = elapsed_ms(t0)


def field_pose(tracker: Tracker, twist: np.ndarray | None) -> np.ndarray:
    """The current pose moved back by the field's lag along ``twist``: the pose this update's field shows."""
    lag = float(tracker._registration.field_lag_ms) * 1e-3
    if twist is None or lag <= 0:
        return tracker._pose
    # ``mat=`` by name: pybind11 takes the matrix overload at once (the same pose).
    return gtsam.Pose3(mat=tracker._pose).compose(gtsam.Pose3.Expmap(-np.asarray(twist, dtype=np.float64) * lag)).matrix()
