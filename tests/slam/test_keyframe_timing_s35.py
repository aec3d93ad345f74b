"""Keyframe decision: the displacement trigger waits ``keyframe_displacement_min_s`` after the last keyframe, the
tracked-points trigger does not."""

from dataclasses import replace

import numpy as np

from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import TrackingConfig
from evpose.slam.local_map import need_keyframe


def _map(n: int = 40) -> tuple[SlamMap, np.ndarray, np.ndarray]:
    """A map whose last keyframe (at t = 1 s) observes ``n`` tracks, each carrying a point; the tracks as seen now."""
    rng = np.random.default_rng(0)
    uv = rng.uniform(20.0, 200.0, (n, 2))
    m = SlamMap(0)
    m.keyframes.append(Keyframe(0, 1_000_000, np.eye(4), {t: uv[t].copy() for t in range(n)}))
    for t in range(n):
        m.points[t] = MapPoint(t, np.array([0.0, 0.0, 2.0]), {0: uv[t].copy()}, track_id=t)
    return m, np.arange(n), uv


def test_displacement_keyframe_waits_for_the_minimum_interval():
    m, ids, uv = _map()
    moved = uv + np.array([30.0, 0.0])  # every key point 30 px away: over the 20 px displacement threshold
    cfg = replace(TrackingConfig(), keyframe_displacement_min_s=0.05)
    assert not need_keyframe(m, ids, moved, len(ids), cfg, t_us=1_030_000)  # 30 ms after the last keyframe
    assert need_keyframe(m, ids, moved, len(ids), cfg, t_us=1_050_000)
    # Off (the default), or without a time, the displacement decides at once.
    assert need_keyframe(m, ids, moved, len(ids), TrackingConfig(), t_us=1_030_000)
    assert need_keyframe(m, ids, moved, len(ids), cfg)


def test_losing_tracked_points_still_makes_a_keyframe_at_once():
    m, ids, uv = _map()
    cfg = replace(TrackingConfig(), keyframe_displacement_min_s=0.05)
    n_few = int(0.5 * len(ids))  # below keyframe_tracked_ratio (0.7) of the last keyframe's tracked points
    assert need_keyframe(m, ids, uv, n_few, cfg, t_us=1_010_000)
    assert not need_keyframe(m, ids, uv, len(ids), cfg, t_us=1_010_000)  # neither trigger
