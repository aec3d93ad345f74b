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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np


@dataclass
class EgoMotionConfig:
    """Parameters of the ego-motion consistency filter."""

    enabled: bool = True
    """Run the filter (False keeps every event)."""
    radius_px: float = field(default=1.0, metadata={"min": 0.5, "max": 6.0, "step": 0.5, "unit": "px"})
    """Support radius around a warped event in the other half-window, pixels."""
    min_separation: float = field(default=0.33, metadata={"min": 0.05, "max": 0.5, "step": 0.01, "unit": "window"})
    """Support must come from an event at least this share of the window span earlier or later (<= 0.5 so every event has such a side)."""
    depth_cell_px: int = field(default=8, metadata={"min": 2, "max": 64, "step": 1, "unit": "px"})
    """Cell size of the coarse map-depth image, pixels."""
    default_depth_m: float = field(default=2.0, metadata={"min": 0.05, "max": 1000.0, "step": 0.05, "unit": "m"})
    """Depth used when no map point is in view, metres."""
    min_events: int = field(default=200, metadata={"min": 0, "max": 100000, "step": 10, "unit": "events"})
    """Windows with fewer events are kept whole (too sparse to judge consistency)."""


@nb.njit(cache=True)
def _depth_grid(uv, z, cell, gw, gh):
    grid = np.full((gh, gw), np.inf)
    for k in range(uv.shape[0]):
        if not (z[k] > 0):
            continue
        cx = int(np.floor(uv[k, 0] / cell))
        cy = int(np.floor(uv[k, 1] / cell))
        if 0 <= cx < gw and 0 <= cy < gh and z[k] < grid[cy, cx]:
            grid[cy, cx] = z[k]
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


class EgoMotionFilter:
    """Keeps the events whose motion the IMU-predicted ego-motion of static structure explains."""

    def __init__(self, config: EgoMotionConfig | None = None):
        self.config = config or EgoMotionConfig()
        self.last_counts: dict = {}

    def depth_image(self, points_world, T_world_cam, K, width: int, height: int) -> np.ndarray:
        """Coarse depth per cell (rows, cols) from map points; empty cells get the median depth."""
        c = self.config
        cell = int(c.depth_cell_px)
        gw, gh = (width + cell - 1) // cell, (height + cell - 1) // cell
        if points_world is None or len(points_world) == 0:
            return np.full((gh, gw), c.default_depth_m)
        T = np.asarray(T_world_cam, np.float64)
        R_cw = T[:3, :3].T
        X = (np.asarray(points_world, np.float64) - T[:3, 3]) @ R_cw.T
        z = X[:, 2]
        front = z > 1e-6
        if not front.any():
            return np.full((gh, gw), c.default_depth_m)
        uv = np.full((X.shape[0], 2), -1.0)
        uv[front, 0] = K[0, 0] * X[front, 0] / z[front] + K[0, 2]
        uv[front, 1] = K[1, 1] * X[front, 1] / z[front] + K[1, 2]
        grid = _depth_grid(uv, np.where(front, z, -1.0), float(cell), gw, gh)
        finite = np.isfinite(grid)
        fill = float(np.median(grid[finite])) if finite.any() else c.default_depth_m
        return np.where(finite, grid, fill)

    def filter(self, x, y, t, T_world_cam, omega_cam, v_world, K, width: int, height: int,
               points_world: np.ndarray | None = None, t_ref_us: int | None = None) -> np.ndarray:
        """Boolean keep mask (E,) for events ``x, y`` (ideal pinhole pixels), ``t`` (us).

        ``T_world_cam`` is the pose at ``t_ref_us`` (default: the window's middle),
        ``omega_cam`` the camera angular rate (camera frame, rad/s) and ``v_world``
        its world velocity (m/s), both assumed constant over the window.
        """
        c = self.config
        ex = np.ascontiguousarray(x, np.float64)
        ey = np.ascontiguousarray(y, np.float64)
        et = np.ascontiguousarray(t, np.int64)
        n = ex.shape[0]
        if not c.enabled or n < max(c.min_events, 2):
            self.last_counts = {"events": n, "events_removed": 0}
            return np.ones(n, bool)
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
        self.last_counts = {"events": n, "events_removed": int(n - np.count_nonzero(keep))}
        return keep
