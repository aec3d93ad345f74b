"""Event-only: a new keyframe's freshly triangulated points checked against the depths the map already holds there
(:class:`KeyframeScaleSettings`, one of the groups of :class:`evpose.slam.tracking_config.TrackingConfig`).

Why: a monocular map's scale lives in its points, and each keyframe hands it on through the points it triangulates. A
keyframe whose new points come out nearer or farther than the older points it sees would pass a wrong scale on
(session 35: indoor seeds 36 and 5 throw their map's scale at one keyframe). The check compares, in the new keyframe,
the depths of its new points with those of the older points it observes, either as a whole (median over median) or
point by point against each new point's nearest older points in the image, and acts on what disagrees by more than
``new_point_depth_ratio``: the new points are scaled about the keyframe's camera centre to the older points' depth
(``level``) or dropped, their tracks left free for a later keyframe to triangulate (``drop``).

Measured (session 36, ``/tmp/s36/eo36``; main e1abba0 defaults, tag ``m35``; event-only, indoor seeds 0-19, 2.161 %):

- What the online ratios see (``diag.py`` hooks every triangulation; ``ana.py``): over the 124 PnP keyframes with at
  least five new and five older points, the log of the new over the older points' median depth (MEDIAN) has an sd of
  0.19 and correlates -0.07 with the oracle log ratio of the new over the older points' depth scale (est / true depth
  in the keyframe, true points triangulated from the same observations at the true poses; sd 0.41); the LOCAL ratio
  (3 nearest older points) +0.07. The older points seen by each new point's keyframe pair, re-triangulated from that
  pair, agree with the map (|median log ratio| 0.005 median, 0.02 at 90 %, 0.08 at most, 160 keyframes): the pair's
  baseline is the map's, so a baseline check has nothing to find. The oracle
  ratio predicts the next keyframe's depth-scale change only weakly (correlation 0.24). Seed 5's scale-throwing
  keyframe (2.34 s, 35 new points) is the one large case both see (MEDIAN 0.60, oracle 0.54); seed 36's (0.18 s) is
  not (MEDIAN 1.05, oracle 1.37): its map's steps go 2-4 times too long over the next 60 ms, a pose problem
  (:mod:`evpose.slam.speed_jump`).
- The option (``batch.sh TAG indoor 0-19 tracking.new_point_depth_ratio=...``, ``sum.py m35 TAG``; paired mean +-
  standard error, seeds better / worse): MEDIAN 1.5 LEVEL 2.238 % (+0.077 +- 0.124, 8 / 6), MEDIAN 1.5 DROP 2.192 %
  (+0.031 +- 0.063, 7 / 7), LOCAL 2 DROP 2.404 % (+0.243 +- 0.166, 6 / 10), LOCAL 2 LEVEL 2.341 % (+0.180 +- 0.188,
  8 / 8). Held out, MEDIAN 1.5 LEVEL: 20-39 2.159 -> 2.255 % (+0.096 +- 0.071, 4 / 8), 40-53 2.064 -> 2.227 % (+0.163
  +- 0.135, 2 / 5); DROP: 2.326 % (+0.167 +- 0.184, 5 / 7), 2.176 % (+0.112 +- 0.142, 2 / 5); seed 36 4.88 -> 5.10 /
  8.49 %.
- Oracles (``oracle.py``, ``orc.sh``: at every event-only keyframe the new points moved along their ray to the true
  depth times the older points' depth scale there): each point on its own 1.995 % (-0.166 +- 0.115, 9 / 11; seeds
  0 / 1 / 5 -1.0 / -1.0 / -1.6); one factor per keyframe (what a scale check can do at best) 2.265 % (+0.104 +-
  0.232, 13 / 7; seed 19 +3.5). Held-out seed 36 (4.88 %): each point 1.95 %, one factor per keyframe 3.70 %. So
  what the oracle mends is each new point's own depth error, not a keyframe-wide scale, and no online ratio finds
  it: at PnP keyframes the new points' scale is no lever worth the 0.16 points the target needs (as session 28 found
  for them, :mod:`evpose.slam.local_map`); the option stays off. Those per-point errors (``diag2.py``, ``ana2.py``;
  1918 new points of seeds 0-19, log of est / true depth less the older points' log depth scale): median |error| 0.16;
  by two-view parallax 1-1.5 / 1.5-2 / 2-3 / 3-5 / over 5 deg 0.37 / 0.18 / 0.16 / 0.11 / 0.15 (10 / 12 / 25 / 24 /
  30 % of the points, 22 / 22 / 22 / 14 / 20 % of the squared error): spread over every parallax, so no parallax
  gate picks them out either.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.geometry import camera_depths


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
    (:attr:`new_point_check`) are acted on by :attr:`new_point_action` (0 or <= 1: off), ratio. Off: 1.5 / 2 under
    every check and action made indoor seeds 0-19 worse (+0.03 to +0.24 points; figures in this module's docstring)."""
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


def new_point_ratios(m: SlamMap, kf: Keyframe, check: NewPointCheck, neighbours: int = 3, min_old: int = 5) -> dict[int, float]:
    """Point id -> depth of each point created at ``kf`` over its reference depth (MEDIAN: the older points' median
    depth in ``kf``; LOCAL: the median depth of its ``neighbours`` nearest older points in ``kf``'s image), for the
    points in front of ``kf``; empty when fewer than ``min_old`` older points ``kf`` observes lie in front of it."""
    new = [p for _, p in sorted(m.points.items()) if p.created_kf == kf.id]
    old = [p for _, p in sorted(m.points.items()) if p.created_kf != kf.id and kf.id in p.obs]
    if not new or not old:
        return {}
    z_old = camera_depths(kf.T_wc, np.stack([p.xyz for p in old]))
    front = z_old > 0
    if front.sum() < min_old:
        return {}
    z_old = z_old[front]
    uv_old = np.stack([p.obs[kf.id] for p, f in zip(old, front) if f])
    z_new = camera_depths(kf.T_wc, np.stack([p.xyz for p in new]))
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

