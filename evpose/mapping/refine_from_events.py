"""Refine a contour map's edge positions from the events of a tracked recording.

A scan places painted (albedo) edges from sparse samples (10 cm apart on the simulated
landing, ~1 cm median error), while an event camera sees them sharply: an event fires
where an edge crosses a pixel centre at the moment it does. Given a trajectory that
already tracks (``full`` mode with the IMU), every event near a point's projected edge
says how far, along the edge's image normal, the edge really lies from the projection.

Per map point, over the updates that registered, the signed distance of each nearby event
(within ``window_px`` across the edge, ``tangent_px`` along it) to the point's projected
edge line is converted to metres along the point's in-plane ``edge_normal`` (divided by
the image displacement per metre of that move) and binned. The projection is taken at
each event's own time (linear between the poses of the update), so the edge's image
motion during an update adds no lag. Histograms of neighbouring points of one edge (same
region, parallel edge normals) are pooled, the dominant peak is located, and the point is
moved by the peak's centroid when the peak stands clearly above the floor of unrelated
events. Iterating (re-track on the refined map, measure again) removes what a pose biased
by the old map left.

Only ``core`` is imported: the caller supplies the trajectory (``evpose refine-map`` runs
the tracker for it), which keeps the mapping layer free of the tracker.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory


@dataclass
class EventRefineConfig:
    """Settings of the event-based map refinement."""

    window_px: float = field(default=4.0, metadata={"min": 0.5, "max": 20.0, "step": 0.5, "unit": "px"})
    """Events up to this far across a point's projected edge count for it, pixels."""
    tangent_px: float = field(default=1.0, metadata={"min": 0.25, "max": 10.0, "step": 0.25, "unit": "px"})
    """Half-width of the strip along the projected edge around the point, pixels."""
    max_shift_m: float = field(default=0.04, metadata={"min": 0.005, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest move considered (histogram half-range), metres."""
    bin_m: float = field(default=0.001, metadata={"min": 0.0001, "max": 0.01, "step": 0.0001, "unit": "m"})
    """Histogram bin along the edge normal, metres."""
    peak_halfwidth_m: float = field(default=0.003, metadata={"min": 0.0005, "max": 0.02, "step": 0.0005, "unit": "m"})
    """Half-width of the window around the peak whose centroid is the move, metres (~the pixel footprint)."""
    min_px_per_m: float = field(default=30.0, metadata={"min": 1.0, "max": 1000.0, "step": 1.0, "unit": "px/m"})
    """Skip a point in an update when a 1 m move along its edge normal shifts its edge less than this, pixels
    (seen edge-on: the offset says little about the position)."""
    min_gain_ratio: float = field(default=0.5, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """... and when it shifts it less than this fraction of a fronto-parallel move (``fx / depth`` px per metre):
    an edge normal seen foreshortened turns a sub-pixel bias of the events into centimetres."""
    deadband_px: float = field(default=0.0, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "px"})
    """Leave a point where it is when the events place its edge less than this far from it in the image, pixels.

    Events sit a fraction of a pixel on the dark side of a sharp edge (the log response is steepest where the
    pixel is darkest), so a map that is right to the millimetre is still "off" by that much."""
    max_curvature: float = field(default=0.01, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "ratio"})
    """Only points with surface variation up to this are measured and moved: brightness (painted) edges inside a flat
    region (~0.001 on the landing map) are placed from sparse intensity steps, while creases (0.03-0.12) are plane
    intersections already right to the millimetre, where the events' sub-pixel bias (``deadband_px``) and the
    pose errors of the refinement flight would only move them off (measured: +1 mm ATE on a separate flight)."""
    pool_radius_m: float = field(default=0.02, metadata={"min": 0.0, "max": 0.2, "step": 0.005, "unit": "m"})
    """Histograms of points of the same region within this distance and with parallel edge normals are pooled, metres."""
    pool_min_cos: float = field(default=0.95, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "cos"})
    """Edge normals count as parallel above this cosine."""
    min_events: int = field(default=40, metadata={"min": 1, "max": 100000, "step": 1, "unit": "events"})
    """A pooled peak needs at least this many events in its window."""
    min_contrast: float = field(default=3.0, metadata={"min": 1.0, "max": 100.0, "step": 0.5, "unit": "ratio"})
    """The peak window's mean count per bin must exceed the histogram's median per bin by this factor."""
    min_depth_m: float = field(default=0.05, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "m"})
    """Points closer than this along the optical axis are ignored, metres."""
    occlusion_cell_px: int = field(default=8, metadata={"min": 2, "max": 64, "step": 1, "unit": "px"})
    """Z-buffer cell: a point deeper than (1 + ``occlusion_tolerance``) x its cell's nearest is hidden, pixels."""
    occlusion_tolerance: float = field(default=0.05, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "ratio"})
    """Relative depth margin of the z-buffer test."""


@dataclass
class EdgeOffsets:
    """What the events said about each map point's edge position."""

    histogram: np.ndarray
    """Events per point and offset bin along the point's edge normal, float32 (N, B); bin ``b`` covers
    ``-max_shift_m + b * bin_m`` .. ``+ bin_m``."""
    updates_seen: np.ndarray
    """Registered updates in which the point was measured, int32 (N,)."""
    gain_sum: np.ndarray
    """Sum over the binned events of the image shift per metre of a move along the edge normal, float64 (N,), px/m."""
    config: EventRefineConfig


@dataclass
class RefineResult:
    """The refined map and how each point moved."""

    contour_map: ContourMap
    shift_m: np.ndarray
    """Move along ``edge_normal`` applied to each point, float64 (N,), metres (0 where not moved)."""
    moved: np.ndarray
    """Points the events placed with confidence, bool (N,)."""
    peak_events: np.ndarray
    """Events in each point's (pooled) peak window, float64 (N,)."""


def _n_bins(cfg: EventRefineConfig) -> int:
    return int(round(2.0 * cfg.max_shift_m / cfg.bin_m))


@numba.njit(cache=True)
def _accumulate(ex, ey, et, t0, t1, pix_start, pix_order, width, height, idx, uv0, uv1, normal, tangent, gain,
                window_px, tangent_px, max_shift, bin_m, hist):
    """Add the events of one update to the histograms of the points ``idx``.

    ``pix_start``/``pix_order``: the update's events bucketed by rounded pixel (CSR). Per point, the projection
    moves linearly from ``uv0`` (time ``t0``) to ``uv1`` (``t1``); ``normal``/``tangent`` are its projected edge's
    unit normal/direction and ``gain`` the px per metre of a move along its edge normal, signed. Returns the
    number of events binned per point."""
    nb = hist.shape[1]
    span = max(t1 - t0, 1)
    reach = window_px + tangent_px + 1.0
    out = np.zeros(idx.shape[0], np.int64)
    for j in range(idx.shape[0]):
        du = uv1[j, 0] - uv0[j, 0]
        dv = uv1[j, 1] - uv0[j, 1]
        ulo = min(uv0[j, 0], uv1[j, 0]) - reach
        uhi = max(uv0[j, 0], uv1[j, 0]) + reach
        vlo = min(uv0[j, 1], uv1[j, 1]) - reach
        vhi = max(uv0[j, 1], uv1[j, 1]) + reach
        c0 = max(int(np.floor(ulo)), 0)
        c1 = min(int(np.ceil(uhi)), width - 1)
        r0 = max(int(np.floor(vlo)), 0)
        r1 = min(int(np.ceil(vhi)), height - 1)
        nx, ny = normal[j, 0], normal[j, 1]
        tx, ty = tangent[j, 0], tangent[j, 1]
        g = gain[j]
        row = idx[j]
        for r in range(r0, r1 + 1):
            for c in range(c0, c1 + 1):
                k = r * width + c
                for q in range(pix_start[k], pix_start[k + 1]):
                    e = pix_order[q]
                    a = (et[e] - t0) / span
                    ox = ex[e] - (uv0[j, 0] + a * du)
                    oy = ey[e] - (uv0[j, 1] + a * dv)
                    if abs(ox * tx + oy * ty) > tangent_px:
                        continue
                    d = ox * nx + oy * ny
                    if abs(d) > window_px:
                        continue
                    s = d / g
                    b = int(np.floor((s + max_shift) / bin_m))
                    if b < 0 or b >= nb:
                        continue
                    hist[row, b] += 1.0
                    out[j] += 1
    return out


def _project(points_world: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    R_cw = T_world_cam[:3, :3].T
    pc = (points_world - T_world_cam[:3, 3]) @ R_cw.T
    z = pc[:, 2]
    zs = np.where(np.abs(z) > 1e-9, z, 1e-9)
    uv = np.stack([K[0, 0] * pc[:, 0] / zs + K[0, 2], K[1, 1] * pc[:, 1] / zs + K[1, 2]], axis=1)
    return uv, z


def _visible(cmap: ContourMap, candidates: np.ndarray, T: np.ndarray, K: np.ndarray, w: int, h: int,
             cfg: EventRefineConfig) -> np.ndarray:
    """Indices of candidate points in the image, in front, facing the camera and not behind a nearer point."""
    pts = cmap.points[candidates]
    uv, z = _project(pts, T, K)
    ok = (z > cfg.min_depth_m) & (uv[:, 0] >= 0) & (uv[:, 0] <= w - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= h - 1)
    # A contour seen from behind its own surface (plane normals face the scanner, i.e. up and out) is hidden.
    pn = cmap.plane_normal[candidates].astype(np.float64)
    view = T[:3, 3] - pts
    facing = np.einsum("ij,ij->i", pn, view) > 0
    ok &= facing | ~np.any(pn != 0, axis=1)
    sel = np.flatnonzero(ok)
    if sel.size == 0:
        return candidates[sel]
    cell = int(cfg.occlusion_cell_px)
    gw = w // cell + 1
    k = (uv[sel, 1] // cell).astype(np.int64) * gw + (uv[sel, 0] // cell).astype(np.int64)
    zbuf = np.full((h // cell + 1) * gw, np.inf)
    np.minimum.at(zbuf, k, z[sel])
    sel = sel[z[sel] <= zbuf[k] * (1.0 + cfg.occlusion_tolerance)]
    return candidates[sel]


def _edge_geometry(cmap: ContourMap, idx: np.ndarray, T: np.ndarray, K: np.ndarray):
    """Per point: projection, unit image normal of its projected edge, unit image tangent, px per metre of a move
    along its edge normal (signed, along the image normal)."""
    p = cmap.points[idx]
    en = cmap.edge_normal[idx].astype(np.float64)
    tan3 = np.cross(cmap.plane_normal[idx].astype(np.float64), en)
    step = 0.01  # metres: small against the distance, large against rounding
    uv, _ = _project(p, T, K)
    du_n = (_project(p + step * en, T, K)[0] - uv) / step
    du_t = (_project(p + step * tan3, T, K)[0] - uv) / step
    tl = np.linalg.norm(du_t, axis=1)
    tangent = du_t / np.where(tl > 0, tl, 1.0)[:, None]
    normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
    gain = np.einsum("ij,ij->i", du_n, normal)
    flip = gain < 0
    normal[flip] *= -1.0
    gain[flip] *= -1.0
    return uv, normal, tangent, gain, tl


def measure_edge_offsets(
    events: EventArray,
    trajectory: Trajectory,
    registered_t_us: np.ndarray,
    calibration: CameraCalibration,
    cmap: ContourMap,
    config: EventRefineConfig | None = None,
) -> EdgeOffsets:
    """Histogram, per map point, of where the events place its edge relative to it (module docstring).

    ``trajectory``: ``T_world_cam`` at the update times; ``registered_t_us``: the update times whose registration
    succeeded (the intervals ending at them are used). Event pixels go through the calibration's undistortion.
    """
    cfg = config or EventRefineConfig()
    n, nb = len(cmap), _n_bins(cfg)
    hist = np.zeros((n, nb), np.float32)
    seen = np.zeros(n, np.int32)
    gain_sum = np.zeros(n)
    K = calibration.K
    w, h = int(calibration.width), int(calibration.height)
    candidates = np.flatnonzero(np.any(cmap.edge_normal != 0, axis=1) & np.any(cmap.plane_normal != 0, axis=1)
                                & (cmap.curvature <= cfg.max_curvature))
    reg = set(int(t) for t in np.asarray(registered_t_us, np.int64))
    t_all = trajectory.t
    if len(t_all) < 2 or candidates.size == 0 or len(events) == 0:
        return EdgeOffsets(hist, seen, gain_sum, cfg)
    if calibration.dist:
        table = calibration.undistortion_table
    poses = trajectory.matrices()
    for i in range(1, len(t_all)):
        t0, t1 = int(t_all[i - 1]), int(t_all[i])
        if t1 not in reg:
            continue
        i0, i1 = events.index_range(t0, t1)
        if i1 <= i0:
            continue
        ev = events[i0:i1]
        if calibration.dist:
            xy = table[ev.y, ev.x].astype(np.float64)
            ex, ey = xy[:, 0].copy(), xy[:, 1].copy()
        else:
            ex, ey = ev.x.astype(np.float64), ev.y.astype(np.float64)
        col = np.clip(np.rint(ex), 0, w - 1).astype(np.int64)
        row = np.clip(np.rint(ey), 0, h - 1).astype(np.int64)
        key = row * w + col
        order = np.argsort(key, kind="stable")
        start = np.searchsorted(key[order], np.arange(w * h + 1)).astype(np.int64)
        T0, T1 = poses[i - 1], poses[i]
        Tm = trajectory.interpolate((t0 + t1) // 2).matrix(0)
        idx = _visible(cmap, candidates, Tm, K, w, h, cfg)
        if idx.size == 0:
            continue
        _, normal, tangent, gain, tl = _edge_geometry(cmap, idx, Tm, K)
        depth = _project(cmap.points[idx], Tm, K)[1]
        good = (gain >= cfg.min_px_per_m) & (gain >= cfg.min_gain_ratio * K[0, 0] / depth) & (tl > 0)
        idx, normal, tangent, gain = idx[good], normal[good], tangent[good], gain[good]
        if idx.size == 0:
            continue
        uv0 = _project(cmap.points[idx], T0, K)[0]
        uv1 = _project(cmap.points[idx], T1, K)[0]
        got = _accumulate(ex, ey, ev.t, t0, t1, start, order, w, h, idx.astype(np.int64), uv0, uv1,
                          np.ascontiguousarray(normal), np.ascontiguousarray(tangent), np.ascontiguousarray(gain),
                          float(cfg.window_px), float(cfg.tangent_px), float(cfg.max_shift_m), float(cfg.bin_m), hist)
        seen[idx[got > 0]] += 1
        gain_sum[idx] += got * gain
    return EdgeOffsets(hist, seen, gain_sum, cfg)


def _pool(cmap: ContourMap, hist: np.ndarray, rows: np.ndarray, cfg: EventRefineConfig) -> np.ndarray:
    """Sum of the histograms of each row's neighbours on the same edge (the row itself included)."""
    if cfg.pool_radius_m <= 0 or rows.size == 0:
        return hist[rows].astype(np.float64)
    from scipy.spatial import cKDTree

    pts = cmap.points[rows]
    pairs = cKDTree(pts).query_pairs(cfg.pool_radius_m, output_type="ndarray")
    en = cmap.edge_normal[rows].astype(np.float64)
    a, b = pairs[:, 0], pairs[:, 1]
    same = (cmap.region_id[rows][a] == cmap.region_id[rows][b]) & (np.einsum("ij,ij->i", en[a], en[b]) >= cfg.pool_min_cos)
    a, b = a[same], b[same]
    local = hist[rows].astype(np.float64)
    pooled = local.copy()
    np.add.at(pooled, a, local[b])
    np.add.at(pooled, b, local[a])
    return pooled


def refine_map(cmap: ContourMap, offsets: EdgeOffsets) -> RefineResult:
    """Move each point along its edge normal to the pooled peak of its offset histogram, where it is clear."""
    cfg = offsets.config
    n, nb = offsets.histogram.shape
    centres = -cfg.max_shift_m + (np.arange(nb) + 0.5) * cfg.bin_m
    shift = np.zeros(n)
    peak_events = np.zeros(n)
    moved = np.zeros(n, bool)
    rows = np.flatnonzero(offsets.histogram.sum(axis=1) > 0)
    if rows.size:
        pooled = _pool(cmap, offsets.histogram, rows, cfg)
        half = max(int(round(cfg.peak_halfwidth_m / cfg.bin_m)), 0)
        kernel = np.ones(2 * half + 1)
        # Peak of the window sums (not of single bins): a ~pixel-wide edge response spreads over several bins.
        win = np.apply_along_axis(lambda r: np.convolve(r, kernel, mode="same"), 1, pooled)
        b = np.argmax(win, axis=1)
        lo = np.clip(b - half, 0, nb - 1)
        hi = np.clip(b + half, 0, nb - 1)
        cols = np.arange(nb)[None, :]
        inwin = (cols >= lo[:, None]) & (cols <= hi[:, None])
        mass = (pooled * inwin).sum(axis=1)
        centroid = (pooled * inwin * centres[None, :]).sum(axis=1) / np.where(mass > 0, mass, 1.0)
        floor = np.median(pooled, axis=1)
        density = mass / (hi - lo + 1)
        inside = (b > half) & (b < nb - 1 - half)  # a peak at the rim may be a larger error cut off: do not trust it
        events = offsets.histogram[rows].sum(axis=1)
        px_per_m = offsets.gain_sum[rows] / np.maximum(events, 1.0)
        ok = (np.abs(centroid) * px_per_m >= cfg.deadband_px) & (mass >= cfg.min_events) & (density >= cfg.min_contrast * np.maximum(floor, 1e-9)) & inside
        shift[rows[ok]] = centroid[ok]
        peak_events[rows] = mass
        moved[rows[ok]] = True
    pts = cmap.points + shift[:, None] * cmap.edge_normal.astype(np.float64)
    refined = ContourMap(pts, cmap.edge_normal, cmap.plane_normal, cmap.region_id, cmap.curvature, cmap.brightness_sign)
    return RefineResult(refined, shift, moved, peak_events)
