"""Merge double contours: one contour per edge, not one per region on either side of it.

Every region traces its own boundary, so a box's crease gets a contour from the top and
one from the side (snapped onto the same intersection line, or a centimetre or two apart
where there was nothing to snap to), and an albedo edge found on both sides of a thin
proud panel appears twice. For the tracker two near-parallel copies of one edge are two
nearby minima of the registration cost; one copy is what the scene has.

Points are visited in order of support - crease-snapped points first (they lie on the
intersection of two fitted planes), then points of larger regions (better plane fits),
then by index - and a point is dropped when an already kept point of *another* region
lies within ``radius``. Points of one region never suppress each other, so a single
contour keeps its spacing. The kept point keeps its normals and sign and moves halfway
towards the mean of the copies it replaced: each region's boundary estimate leans to its
own side of the edge, so the edge lies between them (on a crease both already lie on the
planes' intersection line, and nothing moves).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _greedy_keep(order, region, nb_start, nb_index, points):
    n = order.size
    keep = np.zeros(n, np.bool_)
    dropped = np.zeros(n, np.bool_)
    merged = points.copy()
    for o in range(n):
        i = order[o]
        if dropped[i]:
            continue
        keep[i] = True
        # The edge lies between the two copies: move halfway towards the dropped copy's mean.
        sx = 0.0
        sy = 0.0
        sz = 0.0
        count = 0
        for jj in range(nb_start[i], nb_start[i + 1]):
            j = nb_index[jj]
            # Copies already dropped by a neighbour of i still tell where the edge is.
            if not keep[j] and region[j] != region[i]:
                dropped[j] = True
                sx += points[j, 0]
                sy += points[j, 1]
                sz += points[j, 2]
                count += 1
        if count > 0:
            merged[i, 0] = 0.5 * (points[i, 0] + sx / count)
            merged[i, 1] = 0.5 * (points[i, 1] + sy / count)
            merged[i, 2] = 0.5 * (points[i, 2] + sz / count)
    return keep, merged


def merge_double_contours(points: np.ndarray, region: np.ndarray, priority: np.ndarray,
                          radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Boolean mask (M,) of the contour points to keep and the merged positions (M, 3) (see the module docstring).

    ``points`` (M, 3) m; ``region`` (M,) region of each point; ``priority`` (M,) larger is
    better supported (ties broken by index, so the result is deterministic); ``radius`` m.
    """
    from scipy.spatial import cKDTree

    m = points.shape[0]
    pts = np.ascontiguousarray(points, np.float64)
    if m == 0 or radius <= 0:
        return np.ones(m, bool), pts.copy()
    pairs = cKDTree(pts).query_pairs(radius, output_type="ndarray")
    if pairs.shape[0] == 0:
        return np.ones(m, bool), pts.copy()
    # Only pairs of different regions matter; CSR adjacency in both directions.
    pairs = pairs[region[pairs[:, 0]] != region[pairs[:, 1]]]
    src = np.concatenate([pairs[:, 0], pairs[:, 1]]).astype(np.int64)
    dst = np.concatenate([pairs[:, 1], pairs[:, 0]]).astype(np.int64)
    srt = np.lexsort((dst, src))
    src, dst = src[srt], dst[srt]
    nb_start = np.searchsorted(src, np.arange(m + 1)).astype(np.int64)
    order = np.lexsort((np.arange(m), -np.asarray(priority, np.float64))).astype(np.int64)
    return _greedy_keep(order, np.asarray(region, np.int64), nb_start, dst, pts)
