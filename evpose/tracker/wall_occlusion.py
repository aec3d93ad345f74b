"""Self-occlusion by walls: contour points at the foot of a step are hidden when the camera looks at them over it.

The visible map's z-buffer keeps points within ``occlusion_tolerance`` (5 %) of the nearest depth in their image
cell, so the foot of a low step (the simulated landing's pad: 0.15 m at 3-5 m, 3-5 %) survives even on the sides
where the step hides it. There it projects 2-5 px inside the step's rim and reads the rim's events or its trail,
and pulls the pose by a bias that changes as the view turns (on the true-edge map, dropping the pad's foot on one
side alone took ``stpe`` from 12 to 77-88 mm: that rim then read the foot's events).

A point is a wall foot if another region's contour lies right above it (along its plane normal, which the map
builder points to the side the surface is seen from) just beyond its edge (along its outward edge normal, which
at a region's inner boundary points towards the step). Such a point is hidden when the camera centre lies on the
step's side of it, ``(c - p) . edge_normal > 0``: the wall rises right at the foot, so every ray leaving the foot
towards the step is blocked.
"""

from __future__ import annotations

import hashlib

import numba as nb
import numpy as np

from evpose.core.contour_map import ContourMap


_CACHE: dict[tuple, np.ndarray] = {}
"""Masks by map content and settings: the viewer builds a tracker per parameter change, the mask takes ~0.8 s on the
landing map (97 k points)."""


def wall_foot_mask(contour_map: ContourMap, inward_m: float, radius_m: float, min_height_m: float, max_height_m: float,
                   height_step_m: float = 0.025) -> np.ndarray:
    """(N,) bool (read-only): map points with a point of another region within ``radius_m`` of ``p + inward_m e + h n``
    for some height ``h`` in [``min_height_m``, ``max_height_m``] (``e`` the edge normal, ``n`` the plane normal).

    One KD-tree nearest-neighbour query per height step over the whole map (deterministic), cached by the map's bytes."""
    h = hashlib.sha1()
    for a in (contour_map.points, contour_map.edge_normal, contour_map.plane_normal, contour_map.region_id):
        h.update(np.ascontiguousarray(a).tobytes())
    key = (h.hexdigest(), float(inward_m), float(radius_m), float(min_height_m), float(max_height_m), float(height_step_m))
    if key not in _CACHE:
        if len(_CACHE) > 8:
            _CACHE.clear()
        mask = _wall_feet(contour_map, inward_m, radius_m, min_height_m, max_height_m, height_step_m)
        mask.setflags(write=False)
        _CACHE[key] = mask
    return _CACHE[key]


def _wall_feet(contour_map, inward_m, radius_m, min_height_m, max_height_m, height_step_m) -> np.ndarray:
    from scipy.spatial import cKDTree

    n_pts = len(contour_map)
    out = np.zeros(n_pts, dtype=bool)
    if n_pts == 0 or max_height_m < min_height_m or radius_m <= 0:
        return out
    P = np.asarray(contour_map.points, dtype=np.float64)
    e = np.asarray(contour_map.edge_normal, dtype=np.float64)
    n = np.asarray(contour_map.plane_normal, dtype=np.float64)
    rid = np.asarray(contour_map.region_id)
    known = (np.linalg.norm(e, axis=1) > 0.5) & (np.linalg.norm(n, axis=1) > 0.5) & (rid >= 0)
    if not known.any():
        return out
    tree = cKDTree(P)
    base = P + float(inward_m) * e
    for h in np.arange(float(min_height_m), float(max_height_m) + 0.5 * height_step_m, height_step_m):
        d, j = tree.query(base + h * n, k=1, distance_upper_bound=float(radius_m))
        hit = known & np.isfinite(d)
        jj = np.where(hit, j, 0)
        out |= hit & (rid[jj] != rid) & (rid[jj] >= 0)
    return out


def hidden_by_walls(points: np.ndarray, edge_normal: np.ndarray, feet: np.ndarray, index: np.ndarray,
                    camera_centre: np.ndarray) -> np.ndarray:
    """(len(index),) bool: which of the points ``index`` are wall feet (``feet``) seen over their wall from
    ``camera_centre`` (world, metres)."""
    out = np.zeros(index.size, dtype=bool)
    sel = feet[index]
    if not sel.any():
        return out
    rows = index[sel]
    out[sel] = np.einsum("ij,ij->i", np.asarray(camera_centre, dtype=np.float64)[None, :] - points[rows], edge_normal[rows]) > 0.0
    return out


@nb.njit(cache=True)
def _unhidden_kernel(points, edge_normal, feet, index, c0, c1, c2, out):
    """``index`` without the wall feet seen over their wall from (c0, c1, c2), in order, into ``out``; returns the count.
    The test is :func:`hidden_by_walls`' (its einsum sums the three products in this order)."""
    n = 0
    for k in range(index.shape[0]):
        i = index[k]
        if feet[i] and (c0 - points[i, 0]) * edge_normal[i, 0] + (c1 - points[i, 1]) * edge_normal[i, 1] \
                + (c2 - points[i, 2]) * edge_normal[i, 2] > 0.0:
            continue
        out[n] = i
        n += 1
    return n


def visible_over_walls(points: np.ndarray, edge_normal: np.ndarray, feet: np.ndarray, index: np.ndarray,
                       camera_centre: np.ndarray) -> np.ndarray:
    """``index[~hidden_by_walls(...)]`` in one compiled pass (float64 C-ordered ``points`` / ``edge_normal``): the
    tracker culls with it every update, where the ten small numpy calls of that expression cost ~90 us in a run."""
    out = np.empty(index.shape[0], dtype=np.int64)
    c = np.asarray(camera_centre, dtype=np.float64)
    n = _unhidden_kernel(points, edge_normal, feet, np.ascontiguousarray(index, dtype=np.int64), float(c[0]), float(c[1]),
                         float(c[2]), out)
    return out[:n]
