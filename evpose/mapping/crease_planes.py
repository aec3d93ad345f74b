"""Planes for crease snapping refitted away from the creases, with outliers trimmed.

:func:`evpose.mapping.adjacency.snap_to_intersections` puts a contour point next to another
face on the two regions' planes' intersection. Those planes are the plain least-squares fits of
every point the region holds, and a small region (a crate's side: 20-80 points at 100
points/m^2) holds points of its neighbours: :func:`evpose.mapping.region_growing.extend_to_planes`
hands it any unassigned point within ``plane_distance_m`` of its plane, so a side takes the top's
last points along its rim (2-3 cm inside it, 1-3 cm off the side's plane) and the ground's first
points along its foot. They tilt the side's plane (1.5 degrees on a 0.4 m crate, 5 mm at its top
rim) and offset the top's, and the crease moves with them: the crates' top rims near the landing
pad came out 4-8 mm off along whole runs while most rims are within a millimetre.

Here each region that meets another at a crease gets a second plane: fitted to its points
farther than ``band`` from the plane of every region it meets at a crease (the mixed strip along
each crease is left out), then refitted to the points within ``trim`` robust sigmas (1.4826 MAD)
of that fit (the neighbours' strays further off). A region with too few points left keeps its
plane. The crease-snapped points are moved onto the intersection of the two second planes.
Optionally (``square_deg``) a plane within a few degrees of the largest region's (the ground's)
is made exactly parallel or square to it: with the strays gone, a small face's fitted tilt (its
20-80 points' 5 mm noise over a 0.4 m lever: ~0.5 degrees, 3 mm at the far rim) is still its
crease's largest error.

Measured (session 30, ``/tmp/s30/rim30/``: ``diag.py`` per-point provenance, ``errsx.py`` per-class errors, ``run.py``
tracking; error = distance along the point's edge normal to the nearest true edge, points within 3 cm of one).
Where the top rims > 2 mm off are (2 s landing clouds, 346x260 seeds 0-3, top rims within 4 m of the pad other than
the pad's: 11538 points, 2.10 mm RMS, bias -0.55 mm, 17.5 % > 2 mm): 11453 crease-snapped (1.94 mm RMS, 17.0 % > 2
mm, 85 % of the squared error), 85 moved by ``snap_to_steps`` (9.7 mm RMS, 15 %); by distance to the true edge's end,
< 3 cm 7.4 mm RMS (161 points), 3-10 cm 2.4, 10-30 cm 2.1, > 30 cm 1.3. Most of the error is whole runs of 40-110
points 3-10 mm off (1-1.5 mm spread along the run) on the crates 0.4-0.5 m high, whose faces hold 19-87 points: at
the > 2 mm points the true edge lies 3.9 mm RMS off the partner's plain plane (0.9 mm at the others); e.g. seed 0's
crate side at x = -3.1 m, 41 points, tilted 1.45 degrees by a ground point 20 mm off at its foot (5 mm at the top
rim), or a side holding a top point 2.6 cm inside the rim (-26 mm off its plane). The pad's top rims (4289 points,
5.2 mm RMS, all placed by ``snap_to_steps``) are :mod:`evpose.mapping.step_lines`' concern. Top rims near the pad
(crates' and buildings', seeds 0-3), RMS / bias / > 2 mm: plain 2.10 / -0.55 / 17.5 %; band + trim 2.01 / -0.15 /
14.3 %; with ``square_deg`` 3 1.40 / -0.00 / 2.8 % (the whole map's top rims 1.30 -> 1.07 mm, feet near the pad 1.82
-> 1.60, vertical edges near 2.14 -> 1.41); squared only within 3 standard errors of the tilt
(``square_sigmas`` 3) 1.61 / -0.06 / 3.4 %; band 1 mm (no band) 1.41 / -0.10 / 2.6 %, so the squaring does most.
Tracking (``full``, 2 s landing from ground truth, seeds 0-11, mean ATE, paired against the plain builder run in the
same checkout): see :attr:`evpose.mapping.build.MapBuildConfig.crease_refit`, on by default since session 31 with
``square_deg`` 3 and the feet left as built (seeds 0-23: 346x260 5.088 -> 4.582 mm, 240x180 5.949 -> 5.927, ARE lower
at both; demos, precision / recall and why 240x180 stays level: there).
"""

from __future__ import annotations

import numpy as np


def _fit(p: np.ndarray, up: np.ndarray | None, square_sin: float,
         square_sigmas: float) -> tuple[np.ndarray, np.ndarray]:
    """Centroid and PCA normal of ``p``; the normal made parallel or square to ``up`` when it is within the angle
    whose sine is ``square_sin`` of that (and, ``square_sigmas`` > 0, within that many standard errors of the fit's
    tilt: a face the scan resolves as tilted keeps its tilt)."""
    c = p.mean(axis=0)
    w, v = np.linalg.eigh(np.cov((p - c).T))
    n = v[:, 0]
    if up is None:
        return c, n
    a = float(n @ up)
    parallel = abs(a) >= np.sqrt(1.0 - square_sin * square_sin)
    if not parallel and abs(a) > square_sin:
        return c, n
    if square_sigmas > 0:
        # Tilt standard error: residual RMS / (sqrt(N) x the points' spread along the tilt's lever).
        if parallel:
            lever = float(np.sqrt(max(w[1], 0.0)))
            dev = float(np.arccos(min(abs(a), 1.0)))
        else:
            t = up - a * n
            lever = float(np.std((p - c) @ (t / np.linalg.norm(t))))
            dev = float(np.arcsin(abs(a)))
        se = float(np.sqrt(max(w[0], 0.0))) / (np.sqrt(p.shape[0]) * max(lever, 1e-9))
        if dev > square_sigmas * se:
            return c, n
    if parallel:
        return c, up * (1.0 if a >= 0 else -1.0)
    n = n - a * up
    return c, n / np.linalg.norm(n)


def refit_crease_planes(
    cloud: np.ndarray,
    labels: np.ndarray,
    pairs: np.ndarray,
    plane_c: np.ndarray,
    plane_n: np.ndarray,
    band: float,
    trim: float = 2.5,
    min_points: int = 8,
    iterations: int = 3,
    square_deg: float = 0.0,
    square_sigmas: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Centroids and normals (R, 3) of every region, those in ``pairs`` (P, 2) refitted as the module says.

    ``band`` m: points of a region this close to a crease partner's plane are left out of its fit;
    ``trim``: residual limit in robust sigmas; a region with fewer than ``min_points`` left keeps
    its plane. Normals keep the sign of ``plane_n``. ``square_deg`` > 0: a normal within this angle of
    region 0's (the largest region: the ground, a floor) is made parallel to it, one within it of square
    to it exactly square (a small face's tilt is its fit's largest error); ``square_sigmas`` > 0 only if that
    is also within so many standard errors of the fitted tilt.
    """
    up = plane_n[0] / np.linalg.norm(plane_n[0]) if square_deg > 0 and plane_n.shape[0] else None
    square_sin = float(np.sin(np.radians(square_deg)))
    out_c, out_n = plane_c.copy(), plane_n.copy()
    if pairs.size == 0:
        return out_c, out_n
    partners: dict[int, set[int]] = {}
    for r, s in pairs:
        partners.setdefault(int(r), set()).add(int(s))
        partners.setdefault(int(s), set()).add(int(r))
    order = np.argsort(labels, kind="stable")
    starts = np.searchsorted(labels[order], np.arange(plane_c.shape[0] + 1))
    for r in sorted(partners):
        p = cloud[order[starts[r]:starts[r + 1]]]
        keep = np.ones(p.shape[0], bool)
        for s in sorted(partners[r]):
            keep &= np.abs((p - plane_c[s]) @ plane_n[s]) > band
        p = p[keep]
        if p.shape[0] < min_points:
            continue
        c, n = _fit(p, up, square_sin, square_sigmas)
        for _ in range(iterations):
            res = (p - c) @ n
            sigma = 1.4826 * float(np.median(np.abs(res - np.median(res))))
            inl = np.abs(res) <= trim * max(sigma, 1e-6)
            if inl.sum() < min_points or inl.all():
                break
            p = p[inl]
            c, n = _fit(p, up, square_sin, square_sigmas)
        out_c[r] = c
        out_n[r] = n if float(n @ plane_n[r]) >= 0 else -n
    return out_c, out_n


def resnap_creases(
    before: np.ndarray,
    snapped: np.ndarray,
    region: np.ndarray,
    crease: np.ndarray,
    plane_c: np.ndarray,
    plane_n: np.ndarray,
    max_shift: float,
) -> np.ndarray:
    """``snapped`` with each crease point (``crease`` >= 0) moved to the point of its two regions' (refitted)
    planes' intersection closest to where it was before the snap (``before``), if that is within ``max_shift``."""
    out = snapped.copy()
    sel = np.flatnonzero(crease >= 0)
    if sel.size == 0:
        return out
    r, s = region[sel], crease[sel]
    nr, ns = plane_n[r], plane_n[s]
    hr = np.einsum("md,md->m", nr, plane_c[r])
    hs = np.einsum("md,md->m", ns, plane_c[s])
    p = before[sel]
    g12 = np.einsum("md,md->m", nr, ns)
    det = 1.0 - g12 * g12
    ok = det > 1e-9
    det = np.where(ok, det, 1.0)
    rr = np.einsum("md,md->m", nr, p) - hr
    rs = np.einsum("md,md->m", ns, p) - hs
    x = p - ((rr - g12 * rs) / det)[:, None] * nr - ((rs - g12 * rr) / det)[:, None] * ns
    ok &= np.linalg.norm(x - p, axis=1) < max_shift
    out[sel[ok]] = x[ok]
    return out
