"""Live tracks without a map point that land on an untracked map point's projection take that point over.

A map point lives as long as its KLT track (:mod:`evpose.slam.local_map`); when the track dies, the feature is often
detected again a few MCIs later as a new track, which gets a new point of its own from later (and, after a sparse
stretch, worse) keyframe poses, while the old point stays in the map unseen. Attaching the new track to the old point
keeps the structure seen before and after the gap one set, as ORB-SLAM's fusion of duplicate points does (by
descriptors there, by position here: a match must be near and unambiguous both ways).
"""

from __future__ import annotations

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.geometry import project


def fuse_tracks(m: SlamMap, K: np.ndarray, T_wc: np.ndarray, ids: np.ndarray, uv: np.ndarray, track_to_point: dict[int, int],
                radius_px: float, image_shape: tuple[int, int]) -> int:
    """Attach tracks ``ids`` (pixels ``uv``) without a point of ``m`` to untracked points projecting within ``radius_px``
    by ``T_wc``; returns how many.

    A pair is taken only when each is the other's nearest, and no other candidate of either lies within twice the
    radius: two features near one projection are ambiguous. Updates ``track_to_point`` and the points' ``track_id``.
    """
    if radius_px <= 0 or not m.points or len(ids) == 0:
        return 0
    live = ids.tolist()
    tracked = {track_to_point[t] for t in live if track_to_point.get(t) in m.points}
    free = np.array([i for i, t in enumerate(live) if track_to_point.get(t) not in m.points], np.int64)
    pids = [pid for pid in sorted(m.points) if pid not in tracked]
    if not len(free) or not pids:
        return 0
    proj, z = project(K, invert_pose(T_wc), np.stack([m.points[p].xyz for p in pids]))
    h, w = image_shape
    inside = (z > 0) & (proj[:, 0] >= 0) & (proj[:, 0] < w) & (proj[:, 1] >= 0) & (proj[:, 1] < h)
    if not inside.any():
        return 0
    cand = np.flatnonzero(inside)
    d = np.linalg.norm(uv[free].astype(np.float64)[:, None] - proj[cand][None], axis=2)  # (tracks, points)
    n = 0
    for a in range(len(free)):
        b = int(np.argmin(d[a]))
        if d[a, b] > radius_px or int(np.argmin(d[:, b])) != a:
            continue
        if np.sum(d[a] <= 2 * radius_px) > 1 or np.sum(d[:, b] <= 2 * radius_px) > 1:
            continue
        tid, pid = int(ids[free[a]]), pids[int(cand[b])]
        p = m.points[pid]
        if track_to_point.get(p.track_id) == pid:
            del track_to_point[p.track_id]
        p.track_id = tid
        track_to_point[tid] = pid
        n += 1
    return n

