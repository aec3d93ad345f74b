"""Boundary contours of one planar region: project, rasterise, close, trace, resample, refine.

The region's points are projected onto its plane and rasterised; a morphological closing
bridges sampling gaps and small holes are filled. OpenCV traces every closed boundary
(outer rims and holes). Each chain is smoothed, resampled at an even arc-length spacing
and given its in-plane outward normal (from the loop orientation: outward leaves the
region). Because raster cells quantise the boundary, every contour point is then moved
along its normal to where the region's own points actually end.

The scan's own rim is not an object contour. A contour point is kept only where another
surface lies within ``adjacent_m`` of it (points of other regions, or unassigned points
off this plane, closer than ``adjacent_m`` to the plane) - the wall under a roof edge,
the box standing in a hole of the ground - or where it bounds a hole that contains no
other surface at all (a window or pit the scan saw through). Boundaries where the scan
simply stops have neither and are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

_MAX_CELLS = 40_000_000
"""Largest raster per region; bigger regions get a coarser cell (bounds memory)."""


@dataclass
class RegionContour:
    """Contour points of one region in its plane coordinates."""

    points2d: np.ndarray
    """Positions (a, b) along the region's in-plane axes, float64 (M, 2), metres."""
    normals2d: np.ndarray
    """Unit outward in-plane normals, float64 (M, 2)."""
    keep: np.ndarray
    """False where the point lies on the scan's own rim, bool (M,)."""


def _smooth_closed(chain: np.ndarray, half: int) -> np.ndarray:
    if chain.shape[0] < 2 * half + 3 or half <= 0:
        return chain
    pad = np.concatenate([chain[-half:], chain, chain[:half]])
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    return np.stack([np.convolve(pad[:, d], kernel, mode="valid") for d in range(2)], axis=1)


def _resample_closed(chain: np.ndarray, spacing: float) -> np.ndarray:
    closed = np.vstack([chain, chain[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    length = s[-1]
    if length < 2 * spacing:
        return np.zeros((0, 2))
    n = max(int(round(length / spacing)), 3)
    t = np.arange(n) * (length / n)
    return np.stack([np.interp(t, s, closed[:, d]) for d in range(2)], axis=1)


def _signed_area(chain: np.ndarray) -> float:
    x, y = chain[:, 0], chain[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _disk(radius_cells: int) -> np.ndarray:
    d = 2 * radius_cells + 1
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))


def trace_region(
    own2d: np.ndarray,
    adjacent2d: np.ndarray,
    near2d: np.ndarray,
    cell: float,
    close_cells: int,
    min_hole_m2: float,
    spacing: float,
    adjacent_m: float,
) -> RegionContour:
    """Contour of one region from its projected points.

    ``own2d``: the region's points in plane coordinates (metres). ``adjacent2d``: points of
    other surfaces within ``adjacent_m`` of the plane; ``near2d``: other surfaces further off
    the plane (used to tell a see-through hole from the footprint of an object).
    """
    lo = own2d.min(axis=0)
    hi = own2d.max(axis=0)
    extent = hi - lo
    if (extent[0] / cell + 1) * (extent[1] / cell + 1) > _MAX_CELLS:
        cell = float(np.sqrt(extent[0] * extent[1] / _MAX_CELLS)) * 1.01
    adj_cells = max(1, int(np.ceil(adjacent_m / cell)))
    margin = close_cells + adj_cells + 3
    w = int(np.floor(extent[0] / cell + 0.5)) + 1 + 2 * margin
    h = int(np.floor(extent[1] / cell + 0.5)) + 1 + 2 * margin

    def to_pix(p2):
        ij = np.floor((p2 - lo) / cell + 0.5).astype(np.int64) + margin
        ok = (ij[:, 0] >= 0) & (ij[:, 0] < w) & (ij[:, 1] >= 0) & (ij[:, 1] < h)
        return ij, ok

    def raster(p2):
        g = np.zeros((h, w), np.uint8)
        ij, ok = to_pix(p2)
        g[ij[ok, 1], ij[ok, 0]] = 1
        return g

    occ = raster(own2d)
    if close_cells > 0:
        occ = cv2.morphologyEx(occ, cv2.MORPH_CLOSE, _disk(close_cells))
    # Fill holes smaller than min_hole_m2 (sampling gaps, not structure).
    n_bg, bg_lab, bg_stats, _ = cv2.connectedComponentsWithStats((1 - occ).astype(np.uint8), connectivity=4)
    min_hole_cells = min_hole_m2 / (cell * cell)
    border = np.unique(np.concatenate([bg_lab[0], bg_lab[-1], bg_lab[:, 0], bg_lab[:, -1]]))
    small = np.zeros(n_bg, bool)
    small[1:] = bg_stats[1:, cv2.CC_STAT_AREA] < min_hole_cells
    small[border] = False
    occ[small[bg_lab] & (occ == 0)] = 1

    adjacent = cv2.dilate(raster(adjacent2d), _disk(adj_cells)) if adjacent2d.size else np.zeros_like(occ)
    near = raster(near2d) if near2d.size else np.zeros_like(occ)
    near |= adjacent

    contours, hierarchy = cv2.findContours(occ, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    pts_out, nrm_out, keep_out = [], [], []
    # Chains are in raster steps: smooth over +-2 cells against the staircase, and take
    # tangents and filter refinements over about a cell's worth of resampled points.
    half = 2
    own_tree = None
    span = max(1, int(round(cell / spacing)))
    for ci, c in enumerate(contours):
        chain_pix = c[:, 0, :].astype(np.float64)
        if chain_pix.shape[0] < 4:
            continue
        is_hole = hierarchy[0][ci][3] != -1
        see_through = False
        if is_hole:
            inside = np.zeros_like(occ)
            cv2.drawContours(inside, contours, ci, 1, thickness=cv2.FILLED)
            inside &= 1 - occ
            see_through = not bool(np.any(near & inside))
        chain = (chain_pix - margin) * cell + lo
        chain = _smooth_closed(chain, half)
        p = _resample_closed(chain, spacing)
        if p.shape[0] == 0:
            continue
        tangent = np.roll(p, -span, axis=0) - np.roll(p, span, axis=0)
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
        left = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
        # Left of a counter-clockwise loop is its interior; outward leaves the region,
        # i.e. away from the interior for the outer rim and into it for a hole.
        into_loop = left if _signed_area(chain) > 0 else -left
        outward = into_loop if is_hole else -into_loop
        if own_tree is None:
            from scipy.spatial import cKDTree

            own_tree = cKDTree(own2d)
        p = refine_to_points(p, outward, own_tree, cell, smooth=max(3, int(round(1.5 * cell / spacing))))
        p, outward = straighten(p, outward, eps=3.0 * cell, min_points=max(8, int(round(6 * cell / spacing))), inlier=cell)
        if see_through:
            keep = np.ones(p.shape[0], bool)
        else:
            ij, ok = to_pix(p)
            keep = np.zeros(p.shape[0], bool)
            keep[ok] = adjacent[ij[ok, 1], ij[ok, 0]] > 0
        pts_out.append(p)
        nrm_out.append(outward)
        keep_out.append(keep)
    if not pts_out:
        return RegionContour(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, bool))
    return RegionContour(np.concatenate(pts_out), np.concatenate(nrm_out), np.concatenate(keep_out))


def _mean_projection_table(n: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """Mean of t over the unit disc cut at t <= s, as a function of s in [-1, 1] (monotonic)."""
    t = np.linspace(-1.0, 1.0, 4001)
    chord = 2.0 * np.sqrt(np.maximum(1.0 - t * t, 0.0))
    mass = np.concatenate([[0.0], np.cumsum(0.5 * (chord[1:] + chord[:-1]) * np.diff(t))])
    moment = np.concatenate([[0.0], np.cumsum(0.5 * (t[1:] * chord[1:] + t[:-1] * chord[:-1]) * np.diff(t))])
    s = np.linspace(-1.0, 1.0, n)
    m = np.interp(s, t, moment) / np.maximum(np.interp(s, t, mass), 1e-300)
    m[0] = -1.0
    return s, m


_TABLE_S, _TABLE_M = _mean_projection_table()


def refine_to_points(pts: np.ndarray, outward: np.ndarray, own_tree, cell: float,
                     k: int = 96, smooth: int = 3) -> np.ndarray:
    """Move the points of one closed chain along their normals to where the region's own points end.

    The raster quantises the boundary to a cell and the closing rounds it; the points
    themselves say where the surface ends. Region points sampled evenly fill the part of
    the disc of radius R around a contour point that lies inside the edge; the mean of their
    projections onto the outward normal is a known monotonic function of the edge offset
    (``_TABLE_M``), which is inverted. ``own_tree``: cKDTree over the region's 2D points. Using all points rather than the outermost one gives
    an unbiased, low-variance estimate on sparse scans. The offsets are then median-filtered
    along the chain (``2 * smooth + 1`` points): a sparse boundary is ragged, true edges are not.
    """
    own2d = own_tree.data
    if own2d.shape[0] < 3 or pts.shape[0] == 0:
        return pts
    tree = own_tree
    radius = 2.5 * cell
    dist, idx = tree.query(pts, k=min(k, own2d.shape[0]), distance_upper_bound=radius)
    dist = dist.reshape(pts.shape[0], -1)
    idx = idx.reshape(pts.shape[0], -1)
    valid = np.isfinite(dist)
    safe = np.where(valid, idx, 0)
    proj = np.einsum("mkd,md->mk", own2d[safe] - pts[:, None, :], outward)
    count = valid.sum(axis=1)
    mean = np.where(valid, proj, 0.0).sum(axis=1) / np.maximum(count, 1) / radius
    shift = np.interp(mean, _TABLE_M, _TABLE_S) * radius
    shift[count < 3] = np.nan
    m = pts.shape[0]
    if smooth > 0 and m > 2 * smooth + 1:
        win = np.stack([np.roll(shift, s) for s in range(-smooth, smooth + 1)], axis=1)
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            shift = np.nanmedian(win, axis=1)
    shift = np.clip(np.nan_to_num(shift, nan=0.0), -2.0 * cell, 1.0 * cell)
    return pts + shift[:, None] * outward


def _dp_indices(p: np.ndarray, i0: int, i1: int, eps: float, out: list[int]) -> None:
    """Douglas-Peucker on the open run p[i0..i1]: indices of kept interior vertices (iterative)."""
    stack = [(i0, i1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        d = p[b] - p[a]
        length = float(np.hypot(d[0], d[1]))
        rel = p[a + 1:b] - p[a]
        if length > 0:
            dist = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) / length
        else:
            dist = np.hypot(rel[:, 0], rel[:, 1])
        j = int(np.argmax(dist))
        if dist[j] > eps:
            m = a + 1 + j
            out.append(m)
            stack.append((a, m))
            stack.append((m, b))


def straighten(p: np.ndarray, outward: np.ndarray, eps: float, min_points: int,
               inlier: float, closed: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Replace straight runs of a chain (closed, or open if ``closed`` is False) by their least-squares line.

    Man-made contours are mostly straight; a Douglas-Peucker split (tolerance ``eps``) finds the
    straight runs, and every run of at least ``min_points`` points is projected onto the
    total-least-squares line of its middle part (ends excluded: corners are rounded by the
    raster). Averaging along the run removes the scatter a sparse, noisy scan leaves in
    individual boundary estimates; the line is refitted to the points within ``inlier`` of
    it, so a notch left by a sampling gap at the edge neither tilts nor shifts it.
    Normals of straightened points become the line's normal.
    """
    m = p.shape[0]
    if m < (2 * min_points if closed else min_points):
        return p, outward
    if closed:
        # Start the loop at the point farthest from the first: a vertex of any polygon fit.
        start = int(np.argmax(np.hypot(*(p - p[0]).T)))
        order = np.roll(np.arange(m), -start)
        q = np.vstack([p[order], p[order[:1]]])
        cuts: list[int] = []
        far = int(np.argmax(np.hypot(*(q - q[0]).T)))
        cuts += [0, far, m]
        _dp_indices(q, 0, far, eps, cuts)
        _dp_indices(q, far, m, eps, cuts)
    else:
        # An open chain's ends are vertices; a chain that closes on itself (a traced loop)
        # gets its farthest point as a vertex too, or the end-to-end chord would be degenerate.
        order = np.arange(m)
        far = int(np.argmax(np.hypot(*(p - p[0]).T)))
        cuts = [0, far, m - 1]
        _dp_indices(p, 0, far, eps, cuts)
        _dp_indices(p, far, m - 1, eps, cuts)
        cuts = [m if c == m - 1 else c for c in cuts]  # runs are half-open [a, b): the last point joins the last run
    cuts = sorted(set(cuts))
    out_p = p.copy()
    out_n = outward.copy()
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a < min_points:
            continue
        trim = max(1, (b - a) // 8)
        idx = order[np.arange(a, b) % m]
        core = p[order[np.arange(a + trim, b - trim) % m]]
        for _ in range(3):
            c = core.mean(axis=0)
            _, _, vt = np.linalg.svd(core - c, full_matrices=False)
            direction = vt[0]
            resid = np.abs((core - c) @ np.array([-direction[1], direction[0]]))
            keep = resid <= max(inlier, 2.0 * float(np.median(resid)))
            if keep.all() or keep.sum() < 3:
                break
            core = core[keep]
        normal = np.array([-direction[1], direction[0]])
        if normal @ outward[idx].sum(axis=0) < 0:
            normal = -normal
        t = (p[idx] - c) @ direction
        out_p[idx] = c + t[:, None] * direction
        out_n[idx] = normal
    return out_p, out_n
