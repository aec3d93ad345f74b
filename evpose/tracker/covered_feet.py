"""Feet of vertical faces that the camera sees narrowing towards them: their OFF events trail further behind the edge
than the grazing and crease leads say (see ``EventRegistrationConfig.covered_foot_off_lead_px``).

A box's side seen obliquely from above projects as a strip between its foot (on the ground) and its top rim (nearer the
camera). When the image motion carries the foot away from the strip, the faster top rim sweeps the strip shut
towards the foot: the face narrows and then hides its foot. Session 34 measured (``/tmp/s34/rim34/ana4.py``,
``ana6.py``, ``ana7.py`` on session 33's events registered from the true pose, 240x180 2 s landing seeds 0-1, the built
map) that the OFF events of such feet sit 0.33-0.41 px further behind the foot than its lead says while the strip is
4-12 px wide (a 0.4 m crate's side, both seeds, early and late in the flight), and that these few events (about 3 per
update) carry a fifth of the events' start-up swing along the tilt / shift ridge (+1.0 of +4.9 mm per update from 50
to 600 ms), since they lie on the ground, far below the nearby rims the ridge is told from. Feet whose face widens
(the strip behind the foot's motion, ahead of it) and wide strips (a 2.2 m building's side, 24-80 px) do not: their
OFF events sit +0.09 to +0.12 px ahead of the lead.

The map says which points are feet: a point whose own surface is vertical, or that has a point of a vertical surface
of another region within the crease radius, lies at that vertical region's bottom; the face rises to the region's top.
Which side the face lies on and how wide it is are read per update from the point and the point ``rise`` above it
projected at the registration's pose, and the edge's image motion from the motion twist.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy.spatial import cKDTree

from evpose.tracker.camera_point import camera_point
from evpose.tracker.registration_kernels import _projected_normal


def foot_rise(points: np.ndarray, plane_normals: np.ndarray | None, region_id: np.ndarray | None, radius: float,
              max_vertical_cos: float = 0.3, min_height: float = 0.05) -> np.ndarray:
    """(N,) how far the vertical face above each map point rises (metres, world z up), 0 for points that are not a
    face's foot. ``points`` (N, 3) world metres, ``plane_normals`` (N, 3) their surfaces' unit normals (zero =
    unknown), ``region_id`` (N,) their surface regions (-1 = none). A point's vertical face is its own region if its
    normal's z component is below ``max_vertical_cos`` in absolute value, else the vertical region of a point of
    another region within ``radius`` (the lowest region id, so the choice does not depend on the pair order); the
    point is its foot when it lies nearer the region's lowest point than its highest, and the face rises from the
    point to the highest, if at least ``min_height``. All zero when the normals or regions are unknown or ``radius``
    <= 0."""
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    out = np.zeros(n)
    if plane_normals is None or region_id is None or not float(radius) > 0 or n == 0:
        return out
    pn = np.asarray(plane_normals, dtype=np.float64)
    reg = np.asarray(region_id, dtype=np.int64)
    known = np.einsum("ij,ij->i", pn, pn) > 0.25
    vertical = known & (np.abs(pn[:, 2]) < float(max_vertical_cos)) & (reg >= 0)
    face = np.where(vertical, reg, -1)
    pairs = cKDTree(p).query_pairs(float(radius), output_type="ndarray")
    if len(pairs):
        partner = np.full(n, np.iinfo(np.int64).max)
        for a, b in ((pairs[:, 0], pairs[:, 1]), (pairs[:, 1], pairs[:, 0])):
            sel = ~vertical[a] & vertical[b] & (reg[a] != reg[b])
            np.minimum.at(partner, a[sel], reg[b[sel]])
        take = (face < 0) & (partner != np.iinfo(np.int64).max)
        face[take] = partner[take]
    has = face >= 0
    if not has.any():
        return out
    ids = np.unique(face[has])
    zlo = np.full(ids.size, np.inf)
    zhi = np.full(ids.size, -np.inf)
    in_face = vertical
    k = np.searchsorted(ids, reg[in_face])
    ok = (k < ids.size) & (ids[np.minimum(k, ids.size - 1)] == reg[in_face])
    np.minimum.at(zlo, k[ok], p[in_face, 2][ok])
    np.maximum.at(zhi, k[ok], p[in_face, 2][ok])
    j = np.searchsorted(ids, face[has])
    z = p[has, 2]
    lo, hi = zlo[j], zhi[j]
    foot = (hi - lo >= float(min_height)) & (np.abs(z - lo) < np.abs(z - hi))
    out[np.flatnonzero(has)[foot]] = (hi - z)[foot]
    return out


@nb.njit(cache=True)
def _add_covered_foot_lead(used, points, tangents, rise, R_cw, t_cw, fx, fy, twist, max_width_px, extra, off):  # pragma: no cover - numba
    # Once per registration, for the used feet only: two projections, the image normal and the edge's normal image
    # speed (as the events' kernel reads it, -J . twist), so the per-event kernel is untouched.
    wx, wy, wz, vx, vy, vz = twist[0], twist[1], twist[2], twist[3], twist[4], twist[5]
    n = 0
    for r in range(used.size):
        i = used[r]
        h = rise[i]
        if not h > 0.0 or abs(tangents[i, 2]) > 0.5:
            continue  # not a foot, or a vertical edge (the face's top lies along its own line)
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if not Z > 1e-6:
            continue
        nu, nv = _projected_normal(tangents, i, R_cw, X, Y, Z, fx, fy)
        if nu == 0.0 and nv == 0.0:
            continue
        # the face's top above the point: world +z by h
        Xt, Yt, Zt = X + R_cw[0, 2] * h, Y + R_cw[1, 2] * h, Z + R_cw[2, 2] * h
        if not Zt > 1e-6:
            continue
        iz = 1.0 / Z
        dn = nu * fx * (Xt / Zt - X * iz) + nv * fy * (Yt / Zt - Y * iz)  # the face's far edge along n, pixels
        # a static point's camera-frame velocity under the body twist: -(w x X) - v
        dX = -(wy * Z - wz * Y + vx)
        dY = -(wz * X - wx * Z + vy)
        dZ = -(wx * Y - wy * X + vz)
        vn = nu * fx * (dX * Z - X * dZ) * iz * iz + nv * fy * (dY * Z - Y * dZ) * iz * iz
        if dn * vn < 0.0 and abs(dn) < max_width_px:
            off[r] += extra
            n += 1
    return n


def add_covered_foot_lead(off: np.ndarray, used: np.ndarray, points: np.ndarray, tangents: np.ndarray, rise: np.ndarray,
                          T_world_cam: np.ndarray, K: np.ndarray, twist: np.ndarray, max_width_px: float, extra_px: float) -> int:
    """Adds ``extra_px`` to the OFF lead ``off`` (pixels, as ``used``) of the map points ``used`` (indices into
    ``points`` (N, 3), ``tangents`` (N, 3) their unit edge directions, ``rise`` (N,) of :func:`foot_rise`) that are
    the foot of a vertical face (along a horizontal-ish edge: tangent z at most 0.5) lying behind the foot along its image motion (the body ``twist`` per second, gtsam
    order) and narrower than ``max_width_px`` at ``T_world_cam`` (intrinsics ``K``); returns how many."""
    T = np.asarray(T_world_cam, np.float64)
    R_cw = np.ascontiguousarray(T[:3, :3].T)
    t_cw = -R_cw @ T[:3, 3]
    return int(_add_covered_foot_lead(np.ascontiguousarray(used, np.int64), points, tangents, rise, R_cw, t_cw, float(K[0, 0]),
                                      float(K[1, 1]), np.ascontiguousarray(twist, np.float64), float(max_width_px), float(extra_px),
                                      off))
