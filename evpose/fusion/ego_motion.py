"""Ego-motion infrastructure extraction (EV-Pose section VI-C): drop events the drone's own motion does not explain.

Static structure moves in the image only because the camera moves, with the
motion field given by the IMU-predicted angular rate and velocity and the map
depth. We warp every event of a window to a common reference time with that
field. A static edge keeps firing as it crosses pixels, and all its events,
early and late, land on the same warped place; an independently moving
object's events drift by the object's own motion, so near an event's warped
place there are only events of about the same time (and near a noise event,
none). An event is kept when some event at least ``min_separation`` of the
window span earlier or later lands within ``radius_px`` of it (per-pixel
earliest/latest warped time maps, O(1) per event). Depth comes from the map points projected into coarse cells (nearest
surface per cell); cells without map points take the median map depth.
The tracker's 5 ms batches are too short for the test on their own, so it
passes the last ``history_us`` of events as context (``n_context``): they
support the new events but are not judged again.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np


@dataclass
class EgoMotionConfig:
    """Parameters of the ego-motion consistency filter."""

    enabled: bool = False
    """Run the filter (False keeps every event). Off by default since registration reads ``T_align``
    (:mod:`evpose.fusion.aligned_surface`), which already ignores events away from the map's contours, where most
    moving-object events fall: full mode measured better without it (ATE mm off / on: landing 346x260 20.7 / 21.0,
    240x180 26.0 / 30.9, dynamic-object landing 240x180 18.4 / 20.8) and 1-1.8 ms CPU cheaper per update."""
    radius_px: float = field(default=1.5, metadata={"min": 0.5, "max": 6.0, "step": 0.5, "unit": "px"})
    """Support radius around a warped event in the other half-window, pixels."""
    min_separation: float = field(default=0.33, metadata={"min": 0.05, "max": 0.5, "step": 0.01, "unit": "window"})
    """Support must come from an event at least this share of the window span earlier or later (<= 0.5 so every event has such a side)."""
    depth_cell_px: int = field(default=8, metadata={"min": 2, "max": 64, "step": 1, "unit": "px"})
    """Cell size of the coarse map-depth image, pixels."""
    default_depth_m: float = field(default=2.0, metadata={"min": 0.05, "max": 1000.0, "step": 0.05, "unit": "m"})
    """Depth used when no map point is in view, metres."""
    min_events: int = field(default=200, metadata={"min": 0, "max": 100000, "step": 10, "unit": "events"})
    """Windows with fewer events are kept whole (too sparse to judge consistency)."""
    history_us: int = field(default=20_000, metadata={"min": 0, "max": 100_000, "step": 1000, "unit": "us"})
    """Per-step use (tracker): a step's events are judged within the window of this length ending at the step, earlier events only as support (0 = the batch alone)."""


@nb.njit(cache=True)
def _depth_grid(points, R_cw, p_wc, fx, fy, cx, cy, cell, gw, gh):
    # Nearest map surface per coarse cell; one pass without temporaries (the map has ~1e5 points, run every step).
    grid = np.full((gh, gw), np.inf)
    for k in range(points.shape[0]):
        d0 = points[k, 0] - p_wc[0]
        d1 = points[k, 1] - p_wc[1]
        d2 = points[k, 2] - p_wc[2]
        z = R_cw[2, 0] * d0 + R_cw[2, 1] * d1 + R_cw[2, 2] * d2
        if not (z > 1e-6):
            continue
        X = R_cw[0, 0] * d0 + R_cw[0, 1] * d1 + R_cw[0, 2] * d2
        Y = R_cw[1, 0] * d0 + R_cw[1, 1] * d1 + R_cw[1, 2] * d2
        u = fx * X / z + cx
        v = fy * Y / z + cy
        if not (u > -1e9 and u < 1e9 and v > -1e9 and v < 1e9):
            continue
        gx = int(np.floor(u / cell))
        gy = int(np.floor(v / cell))
        if 0 <= gx < gw and 0 <= gy < gh and z < grid[gy, gx]:
            grid[gy, gx] = z
    return grid


@nb.njit(cache=True)
def _warp(ex, ey, et, t_ref, depth, cell, fx, fy, cx, cy, w, v, out_u, out_v):
    gh, gw = depth.shape
    for i in range(ex.shape[0]):
        u = ex[i]
        vv = ey[i]
        gx = min(max(int(np.floor(u / cell)), 0), gw - 1)
        gy = min(max(int(np.floor(vv / cell)), 0), gh - 1)
        Z = depth[gy, gx]
        x = (u - cx) / fx
        y = (vv - cy) / fy
        X0 = x * Z
        X1 = y * Z
        X2 = Z
        # Static point seen from a moving camera: Xdot = -omega x X - v.
        d0 = -(w[1] * X2 - w[2] * X1) - v[0]
        d1 = -(w[2] * X0 - w[0] * X2) - v[1]
        d2 = -(w[0] * X1 - w[1] * X0) - v[2]
        du = fx * (d0 - x * d2) / Z
        dv = fy * (d1 - y * d2) / Z
        dt = (t_ref - et[i]) * 1e-6
        out_u[i] = u + du * dt
        out_v[i] = vv + dv * dt


@nb.njit(cache=True)
def _support(wu, wv, et, width, height, radius, min_sep_us, keep):
    # Earliest and latest event time landing on each pixel after warping.
    tmin = np.full((height, width), np.iinfo(np.int64).max, np.int64)
    tmax = np.full((height, width), np.iinfo(np.int64).min, np.int64)
    n = wu.shape[0]
    for i in range(n):
        x = int(np.floor(wu[i] + 0.5))
        y = int(np.floor(wv[i] + 0.5))
        if 0 <= x < width and 0 <= y < height:
            if et[i] < tmin[y, x]:
                tmin[y, x] = et[i]
            if et[i] > tmax[y, x]:
                tmax[y, x] = et[i]
    r = int(np.ceil(radius))
    r2 = radius * radius
    for i in range(n):
        x = int(np.floor(wu[i] + 0.5))
        y = int(np.floor(wv[i] + 0.5))
        ok = False
        for yy in range(y - r, y + r + 1):
            if ok or yy < 0 or yy >= height:
                continue
            for xx in range(x - r, x + r + 1):
                if xx < 0 or xx >= width:
                    continue
                if (xx - wu[i]) * (xx - wu[i]) + (yy - wv[i]) * (yy - wv[i]) <= r2 + 0.5:
                    if tmin[yy, xx] <= et[i] - min_sep_us or tmax[yy, xx] >= et[i] + min_sep_us:
                        ok = True
                        break
        keep[i] = ok


_CANDIDATE_MARGIN_PX = 64.0
"""Image margin of the cached depth candidates; the cache is rebuilt before any point can move half of it."""


@nb.njit(cache=True)
def _in_view(points, R_cw, p_wc, fx, fy, cx, cy, width, height, margin, out):
    """Mark points in front of the camera projecting within ``margin`` of the image; returns the nearest such depth."""
    zmin = np.inf
    for k in range(points.shape[0]):
        d0 = points[k, 0] - p_wc[0]
        d1 = points[k, 1] - p_wc[1]
        d2 = points[k, 2] - p_wc[2]
        z = R_cw[2, 0] * d0 + R_cw[2, 1] * d1 + R_cw[2, 2] * d2
        out[k] = False
        if not (z > 1e-6):
            continue
        u = fx * (R_cw[0, 0] * d0 + R_cw[0, 1] * d1 + R_cw[0, 2] * d2) / z + cx
        v = fy * (R_cw[1, 0] * d0 + R_cw[1, 1] * d1 + R_cw[1, 2] * d2) / z + cy
        if -margin <= u < width + margin and -margin <= v < height + margin:
            out[k] = True
            if z < zmin:
                zmin = z
    return zmin


class EgoMotionFilter:
    """Keeps the events whose motion the IMU-predicted ego-motion of static structure explains."""

    def __init__(self, config: EgoMotionConfig | None = None):
        self.config = config or EgoMotionConfig()
        self.last_counts: dict = {}
        self._candidates = None
        """(points array the cache is for, pose it was built at, nearest depth, candidate points) or None."""

    def _depth_candidates(self, points: np.ndarray, T: np.ndarray, K, width: int, height: int) -> np.ndarray:
        """The map points that can project into the image at ``T``: a cached superset, exact for the depth grid.

        Projecting all ~1e5 map points every 5 ms step cost ~0.9 ms. The superset
        (points within ``_CANDIDATE_MARGIN_PX`` of the image at the pose it was built at)
        is reused while the camera has moved less than half that margin of image
        motion for its nearest point, so the grid equals the one from the whole map
        (the bound of the tracker's visible-map cache; a map point nearer than every
        candidate that enters the view within a few steps would be missed until the rebuild).
        """
        c = self._candidates
        f = float(max(K[0, 0], K[1, 1]))
        if c is not None and c[0] is points:
            R_rel = c[1][:3, :3].T @ T[:3, :3]
            angle = float(np.arccos(np.clip((np.trace(R_rel) - 1.0) / 2.0, -1.0, 1.0)))
            dist = float(np.linalg.norm(T[:3, 3] - c[1][:3, 3]))
            if dist < c[2] and f * (1.5 * angle + dist / (c[2] - dist)) < 0.5 * _CANDIDATE_MARGIN_PX:
                return c[3]
        mask = np.empty(points.shape[0], np.bool_)
        zmin = _in_view(points, np.ascontiguousarray(T[:3, :3].T), np.ascontiguousarray(T[:3, 3]), float(K[0, 0]), float(K[1, 1]),
                        float(K[0, 2]), float(K[1, 2]), float(width), float(height), _CANDIDATE_MARGIN_PX, mask)
        cand = np.ascontiguousarray(points[mask])
        # No candidate in view: no bound on what may enter it, so rebuild next time (zmin 0 never validates).
        self._candidates = (points, T.copy(), float(zmin) if np.isfinite(zmin) else 0.0, cand)
        return cand

    def depth_image(self, points_world, T_world_cam, K, width: int, height: int) -> np.ndarray:
        """Coarse depth per cell (rows, cols) from map points; empty cells get the median depth."""
        c = self.config
        cell = int(c.depth_cell_px)
        gw, gh = (width + cell - 1) // cell, (height + cell - 1) // cell
        if points_world is None or len(points_world) == 0:
            return np.full((gh, gw), c.default_depth_m)
        T = np.asarray(T_world_cam, np.float64)
        R_cw = np.ascontiguousarray(T[:3, :3].T)
        pts = self._depth_candidates(np.ascontiguousarray(points_world, np.float64), T, K, width, height)
        grid = _depth_grid(pts, R_cw, np.ascontiguousarray(T[:3, 3]), float(K[0, 0]), float(K[1, 1]),
                           float(K[0, 2]), float(K[1, 2]), float(cell), gw, gh)
        finite = np.isfinite(grid)
        fill = float(np.median(grid[finite])) if finite.any() else c.default_depth_m
        return np.where(finite, grid, fill)

    def filter(self, x, y, t, T_world_cam, omega_cam, v_world, K, width: int, height: int,
               points_world: np.ndarray | None = None, t_ref_us: int | None = None,
               n_context: int = 0) -> np.ndarray:
        """Boolean keep mask (E - n_context,) for events ``x, y`` (ideal pinhole pixels), ``t`` (us).

        The first ``n_context`` events (earlier history) only support the others and are not judged.

        ``T_world_cam`` is the pose at ``t_ref_us`` (default: the window's middle),
        ``omega_cam`` the camera angular rate (camera frame, rad/s) and ``v_world``
        its world velocity (m/s), both assumed constant over the window.
        """
        c = self.config
        ex = np.ascontiguousarray(x, np.float64)
        ey = np.ascontiguousarray(y, np.float64)
        et = np.ascontiguousarray(t, np.int64)
        n = ex.shape[0]
        m = int(n_context)
        if not c.enabled or n < max(c.min_events, 2) or m >= n:
            self.last_counts = {"events": n - m, "events_removed": 0}
            return np.ones(max(n - m, 0), bool)
        t0, t1 = int(et[0]), int(et[-1])
        t_ref = (t0 + t1) // 2 if t_ref_us is None else int(t_ref_us)
        depth = self.depth_image(points_world, T_world_cam, K, width, height)
        R_cw = np.asarray(T_world_cam, np.float64)[:3, :3].T
        v_cam = R_cw @ np.asarray(v_world, np.float64).reshape(3)
        wu = np.empty(n)
        wv = np.empty(n)
        _warp(ex, ey, et, t_ref, depth, float(c.depth_cell_px), K[0, 0], K[1, 1], K[0, 2], K[1, 2],
              np.asarray(omega_cam, np.float64).reshape(3), v_cam, wu, wv)
        keep = np.empty(n, np.bool_)
        min_sep = max(int(c.min_separation * (t1 - t0)), 1)
        _support(wu, wv, et, int(width), int(height), float(c.radius_px), min_sep, keep)
        keep = keep[m:]
        self.last_counts = {"events": n - m, "events_removed": int(keep.size - np.count_nonzero(keep))}
        return keep
