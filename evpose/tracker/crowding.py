"""Map points whose image neighbourhood holds another edge: their TDF minimum is not their own edge's.

Where two edges project within a few pixels of each other (a corner, the top rim
and the contact line of the landing pad seen from above, a crate's rim over the
ground behind it) their time-surface ramps overlap and the blurred field's
minimum sits between them or on the fresher one. Measured on the simulated
landing (true-edge map, registrations from the truth): dropping the points with
another segment's point within 4 px cut the error from 11.6 to 8.0 mm RMS.
Without segment labels (a built map), "another edge" is a neighbour off the
point's own image tangent line by more than a tolerance; with it at 3 px
(``registration_bias_346x260``) the true-edge map's registrations from the truth
end 11.6 / 12.0 -> 8.4 / 7.1 mm RMS away (before / after 0.4 s), the built map's
12.7 / 23.5 -> 11.6 / 22.6 mm, and the TDF-minimum offsets' spread left after the
lag fit falls 0.60 -> 0.41 px per point, 0.25 -> 0.15 px between segments.

One numba pass: bin the projections into square cells of the radius (counting sort), then
test each point against the points of its 3 x 3 cells: 55 us CPU for 1000 points warm, 115 us
median inside the tracker (cold caches), on this machine at load 6. :func:`uncrowded` adds the gathers and the
compaction around it (session 11). Tried there, ``full`` seed 0 at 346x260, kernel CPU median in a run, same
outputs: cells of 4 radii (a 16x smaller grid) 108 -> 160 us (contour points cluster: many more candidates per
cell); int32 grid and keys 89-91 -> 92 us. Session 13: the neighbour test by selects without an exit within a cell
(the same flags), ``_uncrowded_kernel`` on the 393 updates' inputs of that run after 32 MB of other traffic each,
alternated: 133-137 -> 125-129 us median.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.tracker.camera_point import camera_point


@nb.njit(cache=True)
def _crowded_kernel(points, tangents, R_cw, t_cw, fx, fy, cx, cy, radius, tol, out):
    n = points.shape[0]
    u = np.empty(n)
    v = np.empty(n)
    tu = np.zeros(n)
    tv = np.zeros(n)
    ok = np.zeros(n, dtype=np.bool_)  # in front of the camera: a neighbour of others
    has_tangent = np.zeros(n, dtype=np.bool_)  # and its own line is known: it can be tested
    for i in range(n):
        out[i] = False
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if Z <= 1e-6:
            continue
        u[i] = fx * X / Z + cx
        v[i] = fy * Y / Z + cy
        ok[i] = True
        # Image direction of the tangent: d(u, v) / d(metres along it).
        dX = R_cw[0, 0] * tangents[i, 0] + R_cw[0, 1] * tangents[i, 1] + R_cw[0, 2] * tangents[i, 2]
        dY = R_cw[1, 0] * tangents[i, 0] + R_cw[1, 1] * tangents[i, 1] + R_cw[1, 2] * tangents[i, 2]
        dZ = R_cw[2, 0] * tangents[i, 0] + R_cw[2, 1] * tangents[i, 1] + R_cw[2, 2] * tangents[i, 2]
        a = fx * (dX * Z - X * dZ) / (Z * Z)
        b = fy * (dY * Z - Y * dZ) / (Z * Z)
        L = np.sqrt(a * a + b * b)
        if L > 1e-9:
            tu[i] = a / L
            tv[i] = b / L
            has_tangent[i] = True
    # Cells of side ``radius``: every neighbour within it lies in the 3 x 3 cells around a point's own.
    umin = np.inf
    vmin = np.inf
    umax = -np.inf
    vmax = -np.inf
    for i in range(n):
        if ok[i]:
            umin = min(umin, u[i])
            vmin = min(vmin, v[i])
            umax = max(umax, u[i])
            vmax = max(vmax, v[i])
    if not umin <= umax:
        return
    # Cells no smaller than 1/1024 of the spread: still >= the radius for any usable one, but a radius near zero
    # (a config at its bound) or projections far off the image cannot ask for billions of cells.
    cell = max(radius, max(umax - umin, vmax - vmin) / 1024.0)
    gw = int((umax - umin) / cell) + 1
    gh = int((vmax - vmin) / cell) + 1
    # Counting sort of the points by cell (linear time; an argsort of the keys cost half the function).
    key = np.full(n, -1, dtype=np.int64)
    start = np.zeros(gw * gh + 1, dtype=np.int64)
    for i in range(n):
        if ok[i]:
            key[i] = int((v[i] - vmin) / cell) * gw + int((u[i] - umin) / cell)
            start[key[i] + 1] += 1
    for c in range(gw * gh):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(max(start[gw * gh], 1), dtype=np.int64)
    for i in range(n):
        if key[i] >= 0:
            order[fill[key[i]]] = i
            fill[key[i]] += 1
    r2 = radius * radius
    for i in range(n):
        if not has_tangent[i]:
            continue
        ci = int((u[i] - umin) / cell)
        ri = int((v[i] - vmin) / cell)
        found = False
        for dr in range(-1, 2):
            rr = ri + dr
            if rr < 0 or rr >= gh or found:
                continue
            for dc in range(-1, 2):
                cc = ci + dc
                if cc < 0 or cc >= gw or found:
                    continue
                k = rr * gw + cc
                # Selects, not branches: whether a neighbour is near and off the line is unpredictable.
                ui, vi, tui, tvi = u[i], v[i], tu[i], tv[i]
                for s in range(start[k], start[k + 1]):
                    j = order[s]
                    du = u[j] - ui
                    dv = v[j] - vi
                    found |= (du * du + dv * dv <= r2) & (abs(du * tvi - dv * tui) > tol)
        out[i] = found


def crowded_points(points: np.ndarray, tangents: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray, radius_px: float,
                   tolerance_px: float) -> np.ndarray:
    """bool (N,): the points with another of ``points`` within ``radius_px`` of their projection and more than
    ``tolerance_px`` off their own projected tangent line (another edge). Points with an unknown (zero) tangent are
    never crowded themselves but crowd others; points behind the camera take no part."""
    n = points.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    if n == 0 or radius_px <= 0:
        return out
    T = np.asarray(T_world_cam, dtype=np.float64)
    R_cw = np.ascontiguousarray(T[:3, :3].T)  # rigid inverse: no general 4x4 inversion per update
    _crowded_kernel(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(tangents, dtype=np.float64),
                    R_cw, np.ascontiguousarray(-R_cw @ T[:3, 3]), float(K[0, 0]), float(K[1, 1]),
                    float(K[0, 2]), float(K[1, 2]), float(radius_px), float(tolerance_px), out)
    return out


@nb.njit(cache=True)
def _uncrowded_kernel(points_all, tangents_all, used, R_cw, t_cw, fx, fy, cx, cy, radius, tol, out_used, out_pts, out_tan):
    """Rows ``used`` of the map's points and tangents gathered, :func:`_crowded_kernel` on them, and the points it
    does not flag written in order to ``out_*``; returns their count."""
    n = used.shape[0]
    pts = np.empty((n, 3))
    tan = np.empty((n, 3))
    for k in range(n):
        i = used[k]
        for j in range(3):
            pts[k, j] = points_all[i, j]
            tan[k, j] = tangents_all[i, j]
    crowded = np.empty(n, dtype=np.bool_)
    _crowded_kernel(pts, tan, R_cw, t_cw, fx, fy, cx, cy, radius, tol, crowded)
    m = 0
    for k in range(n):
        if crowded[k]:
            continue
        out_used[m] = used[k]
        for j in range(3):
            out_pts[m, j] = pts[k, j]
            out_tan[m, j] = tan[k, j]
        m += 1
    return m


def uncrowded(points_all: np.ndarray, tangents_all: np.ndarray, used: np.ndarray, T_world_cam: np.ndarray, K: np.ndarray,
              radius_px: float, tolerance_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(indices, points (M, 3), tangents (M, 3)) of the map points ``used`` that :func:`crowded_points` does not flag,
    in order: the gathers, the test and the compaction in one compiled call (float64 C-ordered ``points_all`` /
    ``tangents_all``, the whole map's), instead of the six numpy calls around :func:`crowded_points` per update."""
    n = used.shape[0]
    T = np.asarray(T_world_cam, dtype=np.float64)
    R_cw = np.ascontiguousarray(T[:3, :3].T)  # as crowded_points: the same rotation and translation, bit for bit
    out_used, out_pts, out_tan = np.empty(n, dtype=np.int64), np.empty((n, 3)), np.empty((n, 3))
    m = _uncrowded_kernel(points_all, tangents_all, np.ascontiguousarray(used, dtype=np.int64), R_cw,
                          np.ascontiguousarray(-R_cw @ T[:3, 3]), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
                          float(radius_px), float(tolerance_px), out_used, out_pts, out_tan)
    return out_used[:m], out_pts[:m], out_tan[:m]
