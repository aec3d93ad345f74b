"""Feet of vertical faces whose image lies behind them along their image motion: their OFF events sit less far behind
the edge than the crease and grazing leads say (see ``EventRegistrationConfig.covered_foot_off_lead_px``).

A box's side seen obliquely from above projects as a strip between its foot (on the ground) and its top rim (nearer
the camera, so faster in the image). When the image motion carries the foot away from the strip, the rim sweeps the
strip shut towards the foot (the camera flies towards the face: it narrows and then hides its foot); these are the
"covered" feet. Measured (session 34, ``/tmp/s34/rim34/ana10.py`` on session 33's events registered from the true pose,
``decomp.py`` with ``DUMP=1``; 240x180 2 s landing seeds 0-3, the built map; offsets signed along the edge's image
motion, the tracker's gate): the covered feet's OFF events sit -0.13 / -0.16 / -0.18 / -0.16 px from the ground's
points beside the foot (lead -0.22, crease) from 50 to 600 ms and -0.12 / -0.14 (seeds 2 / 3) at 600-1000 ms, -0.26 /
-0.37 / -0.31 / -0.21 px and -0.15 to -0.22 from the face's own foot points (lead -0.28, grazing); as a class
(``ana9.py``) +0.08 to +0.12 px beyond their leads at every face width from 6 to 80 px and in every seed, except one
crate's west foot early in the flight (4-8 px wide, -0.2 to -0.4 px). Uncovered feet's OFF events sit at their leads
(-0.15 to -0.28 px against -0.22 / -0.28). In this flight they are mostly the feet of the buildings beside the start,
which lie on the ground, far below the nearby rims, where the events' tilt / shift ridge is told: +0.1 px on their OFF
lead takes the events' ridge step at the truth (``ana8.py``; mm per update) from +4.44 to +3.50 over 50-600 ms, +0.04
to +0.33 over 600-1000 ms and -1.34 to -1.43 over 1-2 s (seeds 0-3). It is not a property of the class, though: the
3 s landing (6.6 m up, another path; ``ana11.py``, ``ana12.py`` with ``DUR=3``, seeds 0-1) sees covered feet whose
OFF events sit -0.32 / -0.34 px (ground side, lead -0.22) and -0.33 / -0.32 (the face's own, lead -0.28) over its
first 0.6 s, -0.05 px beyond their leads at 12-24 px of face where the 2 s flight's sit +0.08 to +0.11 ahead; so the
lead is an option, off (the closed-loop figures: ``EventRegistrationConfig.covered_foot_off_lead_px``). Nor does the
edge's event multiplicity (events per update over its normal image speed, ``mult.py``) tell the two apart
(correlation with the OFF offset +0.08 to +0.18 per 2 s seed, -0.15 / -0.17 per 3 s seed).

Cost when on (``/tmp/s34/rim34/timing.py``: ``EventRegistration._leads`` on 900 used points of seed 0's 240x180 map at
the true pose 0.3 s in, 655 of them feet, 317 covered; timeit): 12 -> 42 us per registration (the kernel 17 us, its
wrapper 7 us); nothing when off.

The map says which points are feet: a point whose own surface is vertical, or that has a point of a vertical surface
of another region within the crease radius, lies at that vertical region's bottom; the face rises to the region's top.
Which side the face lies on and how wide it is are read per registration from the point and the point ``rise`` above
it projected at the registration's starting pose, and the edge's image motion from the motion twist.
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
