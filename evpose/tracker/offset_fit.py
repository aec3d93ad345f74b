"""The gauge-free fit shared by the two online edge-offset learners (:mod:`evpose.tracker.edge_offsets`, from the
field, and :mod:`evpose.tracker.event_registration`, from the events).

Each learner observes, per map point, how far (pixels along the point's image normal) its edge lies from where the
map puts it. Part of those offsets is the pose's error, not the map's: the 6-DoF pose change that best explains them
is fitted and taken out, and only the rest moves the points along their edge normals. These kernels are that fit:
one point's row, the solve, and the update.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from evpose.tracker.registration_kernels import _damped_step

MIN_FIT_POINTS = 12
"""Fewer points with an offset than this fit no pose change, and nothing moves."""


@nb.njit(cache=True)
def normal_px_per_m(normals, row, R_cw, X, Y, Z, iz, nu, nv, fx, fy):
    """Image displacement along the projected normal ``(nu, nv)`` per metre along the map's edge normal
    ``normals[row]`` of a point at camera coordinates ``(X, Y, Z)`` (``iz`` = 1 / Z); its sign orients the two."""
    ex, ey, ez = normals[row, 0], normals[row, 1], normals[row, 2]
    dX = R_cw[0, 0] * ex + R_cw[0, 1] * ey + R_cw[0, 2] * ez
    dY = R_cw[1, 0] * ex + R_cw[1, 1] * ey + R_cw[1, 2] * ez
    dZ = R_cw[2, 0] * ex + R_cw[2, 1] * ey + R_cw[2, 2] * ez
    return (fx * (dX * Z - X * dZ) * nu + fy * (dY * Z - Y * dZ) * nv) * iz * iz


@nb.njit(cache=True)
def add_offset_row(H, b, jac, j, o, nu, nv, X, Y, Z, pux, puz, pvy, pvz):
    """Row ``j`` of the fit: d(u, v)/d xi projected on the normal (right perturbation, rotation then translation, as
    in :func:`evpose.tracker.registration_kernels._linearise`) into ``jac[j]``, and its normal equations with the
    observed offset ``o`` (pixels) added to ``H`` (6, 6) and ``b`` (6,)."""
    jac[j, 0] = nu * (-puz * Y) + nv * (pvy * Z - pvz * Y)
    jac[j, 1] = nu * (puz * X - pux * Z) + nv * (pvz * X)
    jac[j, 2] = nu * (pux * Y) + nv * (-pvy * X)
    jac[j, 3] = nu * (-pux)
    jac[j, 4] = nv * (-pvy)
    jac[j, 5] = nu * (-puz) + nv * (-pvz)
    for r in range(6):
        b[r] += jac[j, r] * o
        for c in range(6):
            H[r, c] += jac[j, r] * jac[j, c]


@nb.njit(cache=True)
def apply_offset_fit(H, b, n_ok, ok, idx, obs, pxm, jac, offsets, points, base, normals, normals_by_row, gain, max_offset,
                     fit_out):
    """Fit the pose change to the ``n_ok`` rows marked ``ok`` (written to ``fit_out``, left NaN when there are too
    few or it is not finite), then add ``gain`` of each row's remaining offset ``obs[j]`` (pixels, ``pxm[j]`` pixels
    per metre) to ``offsets[idx[j]]`` (metres, clipped to ``max_offset``) and move ``points`` from ``base`` along
    ``normals`` (indexed by row ``j`` when ``normals_by_row``, else by point ``idx[j]``). Returns how many moved."""
    if n_ok < MIN_FIT_POINTS:
        return 0
    # A tiny relative damping keeps the fit finite in the valley the offsets leave unobserved.
    delta = _damped_step(H, -b, 1e-6)
    for r in range(6):
        if not np.isfinite(delta[r]):
            return 0
    for r in range(6):
        fit_out[r] = delta[r]
    moved = 0
    for j in range(idx.shape[0]):
        if not ok[j]:
            continue
        i = idx[j]
        rest = obs[j]
        for r in range(6):
            rest -= jac[j, r] * delta[r]
        off = offsets[i] + gain * rest / pxm[j]
        offsets[i] = min(max(off, -max_offset), max_offset)
        n = j if normals_by_row else i
        for k in range(3):
            points[i, k] = base[i, k] + offsets[i] * normals[n, k]
        moved += 1
    return moved
