"""Event-only: a new keyframe's freshly triangulated points checked against the depths the map already holds there
(:class:`KeyframeScaleSettings`, one of the groups of :class:`evpose.slam.tracking_config.TrackingConfig`).

Why: a monocular map's scale lives in its points, and each keyframe hands it on through the points it triangulates. A
keyframe whose new points come out nearer or farther than the older points it sees would pass a wrong scale on
(session 35: indoor seeds 36 and 5 throw their map's scale at one keyframe). The check compares, in the new keyframe,
the depths of its new points with those of the older points it observes, either as a whole (median over median) or
point by point against each new point's nearest older points in the image, and acts on what disagrees by more than
``new_point_depth_ratio``: the new points are scaled about the keyframe's camera centre to the older points' depth
(``level``) or dropped, their tracks left free for a later keyframe to triangulate (``drop``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap


class NewPointCheck(str, Enum):
    """What :attr:`KeyframeScaleSettings.new_point_depth_ratio` compares."""

    MEDIAN = "median"
    """The median depth of the keyframe's new points against that of the older points it sees (one test, all points)."""
    LOCAL = "local"
    """Each new point's depth against the median depth of its ``new_point_neighbours`` nearest older points in the
    keyframe's image (one test per point; scene depth varies across the image, less between neighbours)."""


class NewPointAction(str, Enum):
    """What happens to new points that fail the check."""

    LEVEL = "level"
    """Scaled about the keyframe's camera centre by the ratio found (MEDIAN: all of them; LOCAL: each to its neighbours)."""
    DROP = "drop"
    """Removed; their tracks keep running without a point, so a later keyframe triangulates them again."""


@dataclass
class KeyframeScaleSettings:
    """Checking a keyframe's new points against the older points' depths (event-only; off by default)."""

    new_point_depth_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 100.0, "step": 0.1, "unit": "ratio"})
    """Event-only: new points whose depth in their keyframe is more than this many times off the older points'
    (:attr:`new_point_check`) are acted on by :attr:`new_point_action` (0 or <= 1: off), ratio."""
    new_point_check: NewPointCheck = NewPointCheck.MEDIAN
    """What ``new_point_depth_ratio`` compares (:class:`NewPointCheck`)."""
    new_point_action: NewPointAction = NewPointAction.LEVEL
    """What ``new_point_depth_ratio`` does to the points that fail (:class:`NewPointAction`)."""
    new_point_neighbours: int = field(default=3, metadata={"min": 1, "max": 50, "step": 1, "unit": "points"})
    """LOCAL check: how many of the nearest older points (in the keyframe's image) give a new point's reference
    depth, points."""
    new_point_min_old: int = field(default=5, metadata={"min": 1, "max": 500, "step": 1, "unit": "points"})
    """Fewest older points in front of the keyframe for the check to run (fewer: the new points are kept as they are),
    points."""


def _depths(kf: Keyframe, X: np.ndarray) -> np.ndarray:
    """Depths (z in ``kf``'s camera, map units) of the world points ``X`` (N, 3)."""
    return (np.asarray(X, np.float64).reshape(-1, 3) - kf.T_wc[:3, 3]) @ kf.T_wc[:3, 2]


def new_point_ratios(m: SlamMap, kf: Keyframe, check: NewPointCheck, neighbours: int = 3, min_old: int = 5) -> dict[int, float]:
    """Point id -> depth of each point created at ``kf`` over its reference depth (MEDIAN: the older points' median
    depth in ``kf``; LOCAL: the median depth of its ``neighbours`` nearest older points in ``kf``'s image), for the
    points in front of ``kf``; empty when fewer than ``min_old`` older points ``kf`` observes lie in front of it."""
    new = [p for _, p in sorted(m.points.items()) if p.created_kf == kf.id]
    old = [p for _, p in sorted(m.points.items()) if p.created_kf != kf.id and kf.id in p.obs]
    if not new or not old:
        return {}
    z_old = _depths(kf, np.stack([p.xyz for p in old]))
    front = z_old > 0
    if front.sum() < min_old:
        return {}
    z_old = z_old[front]
    uv_old = np.stack([p.obs[kf.id] for p, f in zip(old, front) if f])
    z_new = _depths(kf, np.stack([p.xyz for p in new]))
    out: dict[int, float] = {}
    if check is NewPointCheck.MEDIAN:
        ok = z_new > 0
        if not ok.any():
            return {}
        r = float(np.median(z_new[ok])) / float(np.median(z_old))
        return {p.id: r for p, o in zip(new, ok) if o}
    k = min(neighbours, len(z_old))
    for p, z in zip(new, z_new):
        if not z > 0:
            continue
        d = np.linalg.norm(uv_old - p.obs[kf.id], axis=1)
        near = np.argsort(d, kind="stable")[:k]
        out[p.id] = float(z / np.median(z_old[near]))
    return out


def check_new_points(m: SlamMap, kf: Keyframe, track_to_point: dict[int, int], cfg: KeyframeScaleSettings) -> int:
    """Apply :attr:`KeyframeScaleSettings.new_point_depth_ratio` to the points just triangulated at ``kf``; returns how
    many were levelled or dropped (0 when off)."""
    lim = cfg.new_point_depth_ratio
    if not lim > 1.0:
        return 0
    ratios = new_point_ratios(m, kf, cfg.new_point_check, cfg.new_point_neighbours, cfg.new_point_min_old)
    bad = {pid: r for pid, r in ratios.items() if abs(np.log(r)) > np.log(lim)}
    c = kf.T_wc[:3, 3]
    for pid, r in bad.items():
        p = m.points[pid]
        if cfg.new_point_action is NewPointAction.LEVEL:
            p.xyz = c + (p.xyz - c) / r  # along its ray from kf: its observation in kf is unchanged
        else:
            del m.points[pid]
            if track_to_point.get(p.track_id) == pid:
                del track_to_point[p.track_id]
    return len(bad)
