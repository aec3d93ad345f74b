"""Visible map: the contour-map points a camera at a given pose can see.

FoV culling with an expanded margin (the registration may move the pose, so
points just outside the predicted view are kept), a depth range, and occlusion
by a coarse z-buffer: per image cell only points within a depth tolerance of the
nearest point in that cell survive. Contour points of one edge share a depth, so
they survive together; a far edge hidden behind a near surface's contour does
not. One numba pass to project, one to build the z-buffer, one to select.
:class:`VisibleMap` caches a wider superset of the whole map, culled block by
block (bounding spheres of consecutive points), so an update only culls that.

Not kept (session 12, the demo's poses, ~27,000 superset points, same indices out): :func:`_cull_kernel` with a
branch-free projection pass first (138-142 -> 134-137 us), multiplying by the inverse of a power-of-two cell (131-144
us), int32 scratch (140-142 us); the remap of the superset's indices done in the kernel instead of ``sup[...]``
(184 -> 188 us per ``visible``); ``extra_px`` 20 / 40 / 60 / 120 instead of 80 (151 / 80 / 56 / 31 instead of 43
rebuilds over the run, 284-309 us mean per ``visible`` either way, cold). Session 19 (``full`` 346x260 seed 0, in-process
A/B, sessions stepped interleaved, 3 rounds, same poses): the occluding cull of the superset block by block (bounding
spheres of 64 consecutive superset points, rebuilt with it, :func:`_block_cull_kernel`'s test): CPU per update
+0.006 / -0.002 / +0.027 ms median paired, no gain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.tracker.camera_point import camera_point


@dataclass
class VisibleMapConfig:
    """Culling settings."""

    fov_margin_px: float = field(default=20.0, metadata={"min": 0.0, "max": 200.0, "step": 1.0, "unit": "px"})
    """Keep points projecting up to this far outside the image, pixels."""
    min_depth_m: float = field(default=0.05, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "m"})
    """Points closer than this along the optical axis are dropped, metres."""
    max_depth_m: float = field(default=1000.0, metadata={"min": 0.1, "max": 10000.0, "step": 1.0, "unit": "m"})
    """Points farther than this are dropped, metres."""
    occlusion: bool = True
    """Drop points behind the nearest point of their image cell."""
    occlusion_cell_px: int = field(default=8, metadata={"min": 2, "max": 64, "step": 1, "unit": "px"})
    """Side of the z-buffer cells, pixels."""
    occlusion_tolerance: float = field(default=0.05, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "ratio"})
    """A point is occluded if deeper than (1 + this) x the nearest depth in its cell, relative.

    Must be below (object height / camera distance) to cull the hidden back edges of
    low objects: 0.15 kept the far bottom edges of 0.4-0.7 m crates seen from 4 m."""
    crowded_radius_px: float = field(default=3.0, metadata={"min": 0.0, "max": 20.0, "step": 0.5, "unit": "px"})
    """Registration skips the used points with a point of another edge within this distance of their projection
    at the predicted pose (:mod:`evpose.tracker.crowding`; 0 = off), pixels.

    2 s simulated landing from ground truth, built map, mean ATE of seeds 0-3 at 346x260 / 240x180: ``stpe``
    24.48 / 31.10 -> 21.62 / 28.94 mm (ARE 0.353 / 0.475 -> 0.303 / 0.430 deg), ``full`` (``fused_lag_floor_px``
    0) 12.58 / 15.25 -> 11.72 / 12.33 mm (ARE 0.133 / 0.179 -> 0.125 / 0.151 deg). Radius sweep (before points
    without a usable image tangent crowded others): ``stpe`` 2 / 2.5 / 3 px 22.99 / 28.41, 22.13 / 27.95,
    21.79 / 28.49 mm; 4 px, seed 0: 16.1 / 48.2 mm against 18.7 / 29.9; ``full`` 2.5 / 3 px 11.77 / 13.81,
    11.74 / 12.39 mm; tolerance 0.7 / 1.2 / 1.5 px no better. Bundled demo ``landing`` (``--align none``):
    ``full`` 16.81 -> 15.28 mm, ARE 0.215 -> 0.180 deg; ``stpe`` (lost from ~2 s on either way) 125.7 -> 131.8 mm
    (2 px: 124.7, 2.5 px: 135.0), first loss 2.030 -> 2.015 s; ``full`` ``landing_dynamic`` 28.85 -> 24.83 mm,
    ``landing_fast`` 22.66 -> 23.57 mm. The true-edge map, registrations from the truth (bench ``registration_bias``' setting): 11.9 -> 7.4 mm RMS at 3 px.
    Session 7 (``stpe``, seeds 0-3): the radius scaled with the focal length (an angle: 2.08 px at 240x180) took
    240x180 from 23.80 to 22.21 mm (346x260 unchanged, 346x260 radius 2.5 / 3.5 px: 16.05 / 15.68 against 15.82 mm)
    but ``full`` at 240x180 from 9.50 to 10.65 mm, and 1.5 / 2.0 / 2.5 px there gave 23.50 / 21.48 / 23.88 mm (no
    trend): the overlap it guards against is one of blurred pixels, so it stays in pixels."""
    crowded_tolerance_px: float = field(default=1.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "px"})
    """A neighbour belongs to another edge if it lies farther than this from the point's projected tangent line, pixels."""
    wall_occlusion: bool = True
    """Drop wall-foot points (another region's contour right above them) when the camera looks at them over the
    wall (:mod:`evpose.tracker.wall_occlusion`), in ``stpe`` and ``stpe+filter``; the fused modes use
    ``fused_wall_occlusion``.

    The z-buffer's 5 % depth tolerance keeps the hidden foot of the simulated landing's 0.15 m pad, which then
    reads its rim's events (2.6 % of the built map's points are feet). 2 s landing from ground truth, built map,
    session 9 (``/tmp/s9/stpe/run.py``), mean ATE 346x260 / 240x180: ``stpe`` seeds 0-3 13.42 / 19.00 -> 12.40 /
    18.47 mm (ARE 0.206 / 0.256 -> 0.179 / 0.238 deg; seed 0 15.77 -> 13.13 mm, seed 2 11.54 -> 12.99 mm), seeds
    4-7 11.91 / 20.07 -> 11.66 / 20.12 mm (ARE 0.183 / 0.232 -> 0.169 / 0.229 deg); ``stpe+filter`` seeds 0-3
    15.76 / 23.37 -> 14.78 / 21.70 mm. A prototype that turned every plane normal up (19 % of the points flagged),
    inward / radius 0.03 / 0.06, 0 / 0.06, 0.03 / 0.04, 0.03 / 0.1 m: 12.80 / 18.43, 11.96 / 18.61, 12.21 / 18.20,
    12.94 / 18.48 mm (seeds 0-3). A tighter z-buffer instead (``occlusion_tolerance`` 0.03 / 0.02) also culls the
    feet that are in view: 17.9 / 40.0 mm. Bundled demo (``evpose track demo_data/landing.h5 --map
    maps/landing_map.ply --mode stpe``, ``--align none``, lost from ~2 s either way): ATE RMSE 140.1 -> 141.1 mm,
    poses written 399 -> 396."""
    fused_wall_occlusion: bool = False
    """``wall_occlusion`` in the fused modes (``full``), off: ``full`` seeds 0-3 7.78 / 9.40 -> 7.82 / 9.22 mm
    (ARE 0.077 / 0.098 -> 0.075 / 0.096 deg) with it, mixed (the prototype above, inward 0.03 m / radius 0.04 m:
    8.02 / 9.03 mm). Culling costs ~0.05 ms more per update with it (346x260, 0.24 -> 0.29 ms median)."""
    wall_inward_m: float = field(default=0.06, metadata={"min": 0.0, "max": 0.5, "step": 0.01, "unit": "m"})
    """How far beyond a point's edge (along its edge normal) the wall's rim is looked for, metres (the built map puts
    the pad's rim 3-5 cm inside the true one)."""
    wall_radius_m: float = field(default=0.06, metadata={"min": 0.005, "max": 0.5, "step": 0.005, "unit": "m"})
    """Search radius for the rim around each probe position, metres."""
    wall_min_height_m: float = field(default=0.05, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "m"})
    """Lowest step that counts as a wall, metres."""
    wall_max_height_m: float = field(default=0.8, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "m"})
    """Highest wall looked for (probes every 2.5 cm up to it), metres."""


@nb.njit(cache=True, inline="always")
def _in_view(points, i, R_cw, t_cw, fx, fy, cx, cy, margin, umax, vmax, zmin, zmax):
    """(inside, u, v, Z) of map point ``i``: depth first, then each image coordinate only if the previous
    test passed (most points of a superset fail one of them)."""
    px = points[i, 0]
    py = points[i, 1]
    pz = points[i, 2]
    Z = R_cw[2, 0] * px + R_cw[2, 1] * py + R_cw[2, 2] * pz + t_cw[2]
    if not (Z > zmin and Z < zmax):
        return False, 0.0, 0.0, Z
    X = R_cw[0, 0] * px + R_cw[0, 1] * py + R_cw[0, 2] * pz + t_cw[0]
    u = fx * X / Z + cx
    if not (u >= -margin and u <= umax):
        return False, u, 0.0, Z
    Y = R_cw[1, 0] * px + R_cw[1, 1] * py + R_cw[1, 2] * pz + t_cw[1]
    v = fy * Y / Z + cy
    return (v >= -margin and v <= vmax), u, v, Z


@nb.njit(cache=True)
def _cull_kernel(points, R_cw, t_cw, fx, fy, cx, cy, width, height, margin, zmin, zmax, occlusion, cell, tol, out_idx):
    n = points.shape[0]
    gw = int((width + 2 * margin) // cell) + 1
    gh = int((height + 2 * margin) // cell) + 1
    zbuf = np.full(gh * gw, np.inf)
    cand = np.empty(n, dtype=np.int64)
    cell_of = np.empty(n, dtype=np.int64)
    depth = np.empty(n)
    umax = width - 1 + margin
    vmax = height - 1 + margin
    m = 0
    for i in range(n):
        inside, u, v, Z = _in_view(points, i, R_cw, t_cw, fx, fy, cx, cy, margin, umax, vmax, zmin, zmax)
        if not inside:
            continue
        # floor(a / cell) instead of Python's float ``a // cell`` (an fmod per call, 3x slower overall):
        # equal for a >= 0 (guaranteed here) when cell is a power of two (the default 8 px); for other
        # cells they can differ only when a is within one ulp of a cell border.
        k = int(np.floor((v + margin) / cell)) * gw + int(np.floor((u + margin) / cell))
        cand[m] = i
        cell_of[m] = k
        depth[m] = Z
        if Z < zbuf[k]:
            zbuf[k] = Z
        m += 1
    out = 0
    for j in range(m):
        if occlusion and depth[j] > zbuf[cell_of[j]] * (1.0 + tol):
            continue
        out_idx[out] = cand[j]
        out += 1
    return out


@nb.njit(cache=True)
def _bounds_kernel(points, R_cw, t_cw, fx, fy, cx, cy):
    umin = np.inf
    umax = -np.inf
    vmin = np.inf
    vmax = -np.inf
    for i in range(points.shape[0]):
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if Z < 1e-6:
            Z = 1e-6
        u = fx * X / Z + cx
        v = fy * Y / Z + cy
        umin = min(umin, u)
        umax = max(umax, u)
        vmin = min(vmin, v)
        vmax = max(vmax, v)
    return umin, umax, vmin, vmax


def projected_bounds(points_world: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray) -> tuple[float, float, float, float]:
    """(u min, u max, v min, v max) of the points projected with an ideal pinhole ``K``, pixels (depths clamped
    to 1e-6 m); one compiled pass, 10x cheaper than the numpy expression for the ~1000 registered points."""
    T = np.asarray(T_world_cam, dtype=np.float64)
    R_cw = np.ascontiguousarray(T[:3, :3].T)
    t_cw = -R_cw @ T[:3, 3]
    pts = np.ascontiguousarray(points_world, dtype=np.float64)
    return _bounds_kernel(pts, R_cw, t_cw, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]))


def field_box(points_world: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray, pad: int, width: int,
              height: int) -> tuple[int, int, int, int]:
    """(row 0, row 1, column 0, column 1) of the box around the projected points widened by ``pad`` pixels (the
    field's margin and blur radius), clipped to the sensor: the only part of the distance field an update reads."""
    if points_world.shape[0] == 0:
        return (0, 0, 0, 0)
    umin, umax, vmin, vmax = projected_bounds(points_world, T_world_cam, K)
    c0 = int(np.floor(umin)) - pad
    c1 = int(np.ceil(umax)) + pad + 1
    r0 = int(np.floor(vmin)) - pad
    r1 = int(np.ceil(vmax)) + pad + 1
    return (max(r0, 0), min(r1, height), max(c0, 0), min(c1, width))


BLOCK_POINTS = 64
"""Consecutive map points per bounding sphere of the block-wise superset cull (contour maps store neighbours
together: on the simulated landing 64 points span a 0.3 m sphere, median)."""


def point_blocks(points: np.ndarray, block: int = BLOCK_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """(centres (B, 3), radii (B,)) of the bounding spheres of consecutive runs of ``block`` points.

    Radii are padded by 1e-9 relative + 1e-9 m so rounding can never put a point outside its sphere."""
    n = points.shape[0]
    full = n // block
    groups = [points[: full * block].reshape(full, block, 3)] if full else []
    if n > full * block:
        groups.append(points[full * block:][None])
    centres, radii = [np.zeros((0, 3))], [np.zeros(0)]
    for q in groups:
        c = q.mean(axis=1)
        centres.append(c)
        radii.append(np.sqrt(((q - c[:, None, :]) ** 2).sum(axis=2).max(axis=1)) * (1 + 1e-9) + 1e-9)
    return np.concatenate(centres), np.concatenate(radii)


@nb.njit(cache=True)
def _block_cull_kernel(points, centres, radii, block, R_cw, t_cw, fx, fy, cx, cy, width, height, margin, zmin, zmax, out_idx):
    """:func:`_cull_kernel` without occlusion, skipping whole blocks whose bounding sphere lies outside the depth
    range or the widened image; the per-point test is the same expressions, so the same indices come out."""
    umax = width - 1 + margin
    vmax = height - 1 + margin
    n = points.shape[0]
    out = 0
    for b in range(centres.shape[0]):
        r = radii[b]
        Zc = R_cw[2, 0] * centres[b, 0] + R_cw[2, 1] * centres[b, 1] + R_cw[2, 2] * centres[b, 2] + t_cw[2]
        # R_cw's rows are unit vectors, so every point's camera coordinates lie within r of the centre's.
        if Zc + r <= zmin or Zc - r >= zmax:
            continue
        z0 = Zc - r
        if z0 > 0.0 and fx > 0.0 and fy > 0.0:
            z1 = Zc + r
            Xc = R_cw[0, 0] * centres[b, 0] + R_cw[0, 1] * centres[b, 1] + R_cw[0, 2] * centres[b, 2] + t_cw[0]
            Yc = R_cw[1, 0] * centres[b, 0] + R_cw[1, 1] * centres[b, 1] + R_cw[1, 2] * centres[b, 2] + t_cw[1]
            # X / Z over the box [Xc - r, Xc + r] x [z0, z1] (z0 > 0) takes its extremes at the corners; one
            # pixel of slack against rounding.
            umin_b = fx * min((Xc - r) / z0, (Xc - r) / z1) + cx
            umax_b = fx * max((Xc + r) / z0, (Xc + r) / z1) + cx
            vmin_b = fy * min((Yc - r) / z0, (Yc - r) / z1) + cy
            vmax_b = fy * max((Yc + r) / z0, (Yc + r) / z1) + cy
            if umin_b > umax + 1.0 or umax_b < -margin - 1.0 or vmin_b > vmax + 1.0 or vmax_b < -margin - 1.0:
                continue
        for i in range(b * block, min((b + 1) * block, n)):
            if not _in_view(points, i, R_cw, t_cw, fx, fy, cx, cy, margin, umax, vmax, zmin, zmax)[0]:
                continue
            out_idx[out] = i
            out += 1
    return out


def visible_points(points_world: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray, width: int, height: int, config: VisibleMapConfig) -> np.ndarray:
    """Indices (int64, ascending) of the map points visible from ``T_world_cam`` with an ideal pinhole ``K``."""
    T = np.asarray(T_world_cam, dtype=np.float64)
    R_cw = np.ascontiguousarray(T[:3, :3].T)
    t_cw = -R_cw @ T[:3, 3]
    out = np.empty(points_world.shape[0], dtype=np.int64)
    n = _cull_kernel(
        points_world, R_cw, t_cw, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
        int(width), int(height), float(config.fov_margin_px), float(config.min_depth_m), float(config.max_depth_m),
        bool(config.occlusion), float(config.occlusion_cell_px), float(config.occlusion_tolerance), out,
    )
    return out[:n].copy()


@nb.njit(cache=True)
def _moved_little(T0, T, f, zmin, limit):
    """Whether the worst-case image motion (pixels, focal length ``f``) of a point at depth >= ``zmin`` between the
    poses ``T0`` and ``T`` stays below ``limit``: rotation moves every point by <= f * angle (small angles, with 1.5x
    slack), translation moves a point at depth z by <= f * dist / (z - dist)."""
    trace = 0.0  # trace(R0^T R)
    for i in range(3):
        for j in range(3):
            trace += T0[i, j] * T[i, j]
    angle = math.acos(min(max((trace - 1.0) / 2.0, -1.0), 1.0))
    d2 = 0.0
    for i in range(3):
        d2 += (T[i, 3] - T0[i, 3]) ** 2
    dist = math.sqrt(d2)
    if dist >= zmin:
        return False
    return f * (1.5 * angle + dist / (zmin - dist)) < limit


@nb.njit(cache=True)
def _min_depth(points, T):
    """Smallest depth (metres along the optical axis of the camera pose ``T``) of ``points`` (N >= 1, 3): one pass
    instead of the whole (N, 3) product of the camera-frame points."""
    z = np.inf
    for i in range(points.shape[0]):
        d = (points[i, 0] - T[0, 3]) * T[0, 2] + (points[i, 1] - T[1, 3]) * T[1, 2] + (points[i, 2] - T[2, 3]) * T[2, 2]
        z = min(z, d)
    return z


class VisibleMap:
    """Culling with a cached superset: a wider cull is redone only when the camera moved enough to matter.

    The superset is culled with ``extra_px`` more margin and without occlusion; as
    long as the camera has moved less than ``extra_px`` of image motion for the
    nearest superset point, every point the exact cull would consider lies in the
    superset, so the result equals :func:`visible_points` on the whole map, at a
    fraction of the cost for large maps.
    """

    def __init__(self, points_world: np.ndarray, K: np.ndarray, width: int, height: int, extra_px: float = 80.0):
        self.points = np.ascontiguousarray(points_world, dtype=np.float64)
        self.K = np.asarray(K, dtype=np.float64)
        self.width = int(width)
        self.height = int(height)
        self.extra_px = float(extra_px)
        self._cache: tuple[np.ndarray, np.ndarray, float] | None = None
        """(pose the superset was culled at, superset indices, nearest superset depth in metres)."""
        self._sup_points = np.zeros((0, 3))
        self._blocks: tuple[np.ndarray, np.ndarray] | None = None
        """Bounding spheres of consecutive point runs (:func:`point_blocks`), built on the first superset cull."""

    def _superset(self, T: np.ndarray, wide: VisibleMapConfig) -> np.ndarray:
        """:func:`visible_points` of the whole map without occlusion, block by block (4x faster on the landing map)."""
        if self._blocks is None:
            self._blocks = point_blocks(self.points)
        R_cw = np.ascontiguousarray(T[:3, :3].T)
        t_cw = -R_cw @ T[:3, 3]
        out = np.empty(self.points.shape[0], dtype=np.int64)
        K = self.K
        n = _block_cull_kernel(
            self.points, self._blocks[0], self._blocks[1], BLOCK_POINTS, R_cw, t_cw, float(K[0, 0]), float(K[1, 1]),
            float(K[0, 2]), float(K[1, 2]), self.width, self.height, float(wide.fov_margin_px),
            float(wide.min_depth_m), float(wide.max_depth_m), out,
        )
        return out[:n].copy()

    def _still_valid(self, T_world_cam: np.ndarray) -> bool:
        if self._cache is None:
            return False
        T0, _, zmin = self._cache
        # One compiled call: this runs every update, where a 3x3 product, np.trace and np.linalg.norm cost ~30 us (cold,
        # in a run) and the same on Python floats ~20 us (session 19). The test has slack (1.5x the angle), so its
        # rounding cannot change which points are visible, only, at a border case, whether the superset is rebuilt
        # (the result is the same either way).
        return bool(_moved_little(T0, np.asarray(T_world_cam, dtype=np.float64), max(float(self.K[0, 0]), float(self.K[1, 1])),
                                  float(zmin), 0.5 * self.extra_px))

    def visible(self, T_world_cam: np.ndarray, config: VisibleMapConfig) -> np.ndarray:
        """Indices (ascending) of the visible points, as :func:`visible_points` gives them."""
        T = np.asarray(T_world_cam, dtype=np.float64)
        if not self._still_valid(T):
            wide = VisibleMapConfig(
                fov_margin_px=config.fov_margin_px + self.extra_px, min_depth_m=config.min_depth_m,
                max_depth_m=config.max_depth_m, occlusion=False,
            )
            sup = self._superset(T, wide)
            self._sup_points = np.ascontiguousarray(self.points[sup])  # gathered once, reused below
            if sup.size:
                zmin = float(_min_depth(self._sup_points, T))  # only bounds the rebuild test (see _still_valid)
            else:
                zmin = float(config.min_depth_m)
            self._cache = (T.copy(), sup, max(zmin, float(config.min_depth_m), 1e-6))
        sup = self._cache[1]
        if sup.size == 0:
            return sup.copy()
        return sup[visible_points(self._sup_points, T, self.K, self.width, self.height, config)]

    def snapshot(self) -> dict:
        return {"cache": None if self._cache is None else (np.copy(self._cache[0]), np.copy(self._cache[1]), self._cache[2])}

    def restore(self, state: dict) -> None:
        c = state["cache"]
        self._cache = None if c is None else (np.copy(c[0]), np.copy(c[1]), c[2])
        if c is not None:
            self._sup_points = np.ascontiguousarray(self.points[c[1]])
