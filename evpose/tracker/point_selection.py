"""Which map points an update registers: those in view at the predicted pose (over walls too), less the painted points
the refiner has not placed yet, subsampled, less those whose field another edge's overlaps.

Called by :meth:`Tracker.step <evpose.tracker.tracker.Tracker.step>` with its prediction; the settings are the tracker's
``visible_map`` and ``registration`` configs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from evpose.tracker.crowding import uncrowded
from evpose.tracker.registration import strided_subset
from evpose.tracker.wall_occlusion import visible_over_walls

if TYPE_CHECKING:
    from evpose.tracker.tracker import Tracker


def registered_points(tracker: Tracker, predicted: np.ndarray) -> tuple:
    """``(visible, used, pts, used_tangents, skip)`` at the predicted ``T_world_cam``.

    ``visible`` (N,) are the map indices in view, ``used`` (M,) those registered, ``pts`` (M, 3) their points,
    ``used_tangents`` (M, 3) their edge directions when the crowding test gathered them (else None), ``skip`` (N,) bool
    over the map when ``T_align`` is to show held-out painted points that registration skips (else None).
    """
    visible = tracker.visible_map.visible(predicted, tracker.config.visible_map)
    if tracker._wall_feet is not None and visible.size:
        # Feet seen over their wall read the rim's events (see evpose.tracker.wall_occlusion).
        visible = visible_over_walls(tracker._points, tracker._edge_normals, tracker._wall_feet, visible, predicted[:3, 3])
    # Painted points the refiner has not yet placed would pull the pose towards their map error.
    held = (None if tracker.refiner is None or (tracker.polarity_selector is not None and not tracker._hold_filtered)
            else tracker.refiner.held_out())
    candidates, skip = visible, None  # skip: (N,) bool, points whose patches T_align shows but registration skips
    if held is not None:
        ready = ~held[visible]
        if 2 * int(np.count_nonzero(ready)) >= visible.size:  # else the painted points are the map: keep them
            # T_align shows the composed points' patches alone: a point left out of them would never be refined.
            candidates, skip = (visible[ready], None) if tracker.polarity_selector is None else (visible, held)
    cap = float(tracker.config.map_refinement.fused_painted_max_share)
    if cap > 0 and tracker.refiner is not None and tracker.components.drives_pose and candidates.size:
        candidates, skip = capped_painted(tracker, candidates, skip, cap)
    used = strided_subset(candidates, int(tracker.config.registration.max_points))
    vm = tracker.config.visible_map
    used_tangents = None  # the rows of ``used`` of ``_tangents`` once gathered
    if vm.crowded_radius_px > 0 and used.size:
        # Another edge's TDF overlaps theirs: their minimum is not their edge's (see evpose.tracker.crowding).
        used, pts, used_tangents = uncrowded(tracker._points, tracker._tangents, used, predicted, tracker.K,
                                             vm.crowded_radius_px, vm.crowded_tolerance_px)
    else:
        pts = np.take(tracker._points, used, axis=0)  # the rows of ``used``; 3x cheaper than fancy indexing
    return visible, used, pts, used_tangents, skip


def capped_painted(tracker: Tracker, candidates: np.ndarray, skip: np.ndarray | None, cap: float) -> tuple:
    """``(candidates, skip)`` with the painted points among ``candidates`` thinned (an even stride) to ``cap`` of them
    (``MapRefinementConfig.fused_painted_max_share``); the dropped ones are skipped by registration but, with the
    polarity filter, keep their ``T_align`` patches (``skip``, bool over the map), so the refiner still reads them."""
    painted = tracker._painted_mask()
    is_p = painted[candidates]
    n_p = int(np.count_nonzero(is_p))
    keep = int(cap / (1.0 - cap) * (candidates.size - n_p)) if cap < 1.0 else n_p
    if n_p <= keep:
        return candidates, skip
    p_idx = candidates[is_p]
    dropped = np.ones(n_p, dtype=np.bool_)
    dropped[(np.arange(keep) * (n_p / max(keep, 1))).astype(np.int64) if keep > 0 else np.zeros(0, np.int64)] = False
    if tracker.polarity_selector is None:
        return np.sort(np.concatenate([candidates[~is_p], p_idx[~dropped]])), skip
    out = np.zeros(painted.shape[0], dtype=np.bool_) if skip is None else skip.copy()
    out[p_idx[dropped]] = True
    return candidates, out
