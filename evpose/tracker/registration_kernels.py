"""The compiled per-linearisation kernels of :mod:`evpose.tracker.registration`: robust weights, the lag floor's
sampling shift, residuals + weighted normal equations at one pose, and the damped 6x6 LM step.

One numba pass per linearisation and one per step keep the LM loop's Python calls few; the SE(3) algebra and
the prior's terms stay in gtsam / numpy in the caller, whose rounding a compiled copy would not reproduce.

Tried (session 11, 2 s landing seed 0 at 346x260, load ~3, medians alternated against the tree before, outputs
bit-identical): the gradients taken from the field's values at the four pixels (as the curvature is), so the
field need not write its two gradient images: the TDF 26-41 us faster per update, registration 17-44 us slower
(the extra arithmetic per point and linearisation; an in-run linearisation costs about what a warm one does,
~65 ns per point, so the images' cache lines were not what it waited on): no net gain, not kept.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.frontend.distance_field import bilinear_curvature_from_value, bilinear_sample
from evpose.tracker.camera_point import camera_point, fill_image_rows


@nb.njit(cache=True, inline="always")
def _rho_weight(r, loss, k):
    """(rho(r), IRLS weight rho'(r)/r) of a residual for the chosen loss with scale ``k``."""
    a = abs(r)
    if loss == 1:
        if a <= k:
            return 0.5 * r * r, 1.0
        return k * (a - 0.5 * k), k / a
    if loss == 2:
        q = (r / k) ** 2
        return 0.5 * k * k * np.log1p(q), 1.0 / (1.0 + q)
    if loss == 3:
        if a >= k:
            return k * k / 6.0, 0.0
        q = 1.0 - (r / k) ** 2
        return k * k / 6.0 * (1.0 - q * q * q), q * q
    return 0.5 * r * r, 1.0


@nb.njit(cache=True, inline="always")
def _projected_normal(tangents, i, R_cw, X, Y, Z, fx, fy):
    """Unit image normal (nu, nv) of point ``i``'s edge (its world tangent projected at camera point X, Y, Z);
    (0, 0) when the map does not know the tangent or it projects to a point."""
    tx, ty, tz = tangents[i, 0], tangents[i, 1], tangents[i, 2]
    dX = R_cw[0, 0] * tx + R_cw[0, 1] * ty + R_cw[0, 2] * tz
    dY = R_cw[1, 0] * tx + R_cw[1, 1] * ty + R_cw[1, 2] * tz
    dZ = R_cw[2, 0] * tx + R_cw[2, 1] * ty + R_cw[2, 2] * tz
    a = fx * (dX * Z - X * dZ)
    c = fy * (dY * Z - Y * dZ)
    L = np.sqrt(a * a + c * c)
    if L <= 0.0:
        return 0.0, 0.0
    return -c / L, a / L


@nb.njit(cache=True, inline="always")
def _floor_shift(tangents, i, R_cw, X, Y, Z, fx, fy, Ju, Jv, twist, lag_px_per_px_s, floor_px, extra_px):
    """(du, dv): how far behind its projection point ``i``'s TDF minimum lies beyond what the lag explains.

    Along the projected edge normal, oriented against the image motion, by ``floor_px - lag * normal speed``
    when positive (slow edges: see ``RegistrationConfig.lag_floor_px``), plus the point's own ``extra_px``
    (negative: ahead), else (0, 0). ``Ju`` / ``Jv`` are the point's image rows, so ``Ju . twist`` is its image
    velocity (px/s)."""
    nu, nv = _projected_normal(tangents, i, R_cw, X, Y, Z, fx, fy)
    if nu == 0.0 and nv == 0.0:
        return 0.0, 0.0
    vu = 0.0
    vv = 0.0
    for j in range(6):
        vu += Ju[j] * twist[j]
        vv += Jv[j] * twist[j]
    vn = vu * nu + vv * nv
    e = max(floor_px - lag_px_per_px_s * abs(vn), 0.0) + extra_px
    if e == 0.0:
        return 0.0, 0.0
    if vn < 0.0:
        e = -e
    return -e * nu, -e * nv


@nb.njit(cache=True)
def _linearise(points, slots, R_cw, t_cw, fx, fy, cx, cy, value, grad_u, grad_v, box, second_order, loss, k, inlier_thr, H, b, res, wts, uv,
               tangents, twist, lag_s, floor_px, extra, normal_only):
    """Residuals, weights, projections and the weighted normal equations at one pose.

    ``floor_px`` > 0 samples each point's field behind its projection by :func:`_floor_shift` (``tangents`` (M, 3)
    world edge directions, ``twist`` (6,) body twist per second, ``lag_s`` the lag the pose already carries);
    ``extra`` (M,) per-point trail beyond that, pixels (empty = none; it also needs the tangents and twist).
    ``normal_only`` keeps only the field's gradient and curvature along each point's projected edge normal (needs
    ``tangents``; points without a tangent keep both directions).
    Returns (cost, points inside the image, inliers, sum of w r^2, sum of w r^2 over the inliers).
    """
    for i in range(6):
        b[i] = 0.0
        for j in range(6):
            H[i, j] = 0.0
    cost = 0.0
    inside = 0
    inl = 0
    swr2 = 0.0
    swr2_in = 0.0
    J = np.empty(6)
    Ju = np.empty(6)
    Jv = np.empty(6)
    Q1 = np.empty(6)
    Q2 = np.empty(6)
    for i in range(points.shape[0]):
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        res[i] = 1.0
        wts[i] = 0.0
        if Z <= 1e-6:
            uv[i, 0] = np.nan
            uv[i, 1] = np.nan
            continue
        iz = 1.0 / Z
        u = fx * X * iz + cx
        v = fy * Y * iz + cy
        uv[i, 0] = u
        uv[i, 1] = v
        # Rows of d(u, v)/d xi: p_u = d u/dX, p_v = d v/dX; d/domega = p x X, d/dv = -p.
        pux = fx * iz
        puz = -fx * X * iz * iz
        pvy = fy * iz
        pvz = -fy * Y * iz * iz
        Ju[4] = 0.0
        Jv[3] = 0.0
        fill_image_rows(X, Y, Z, pux, puz, pvy, pvz, Ju, Jv)
        us = u
        vs = v
        if floor_px > 0.0 or extra.shape[0]:
            # The shift is held constant within a linearisation (it changes with the pose only through the
            # point's image velocity and normal, a second-order effect).
            du, dv = _floor_shift(tangents, i, R_cw, X, Y, Z, fx, fy, Ju, Jv, twist, lag_s, floor_px,
                                  extra[i] if extra.shape[0] else 0.0)
            us += du
            vs += dv
        f, fu, fv, ok = bilinear_sample(value, grad_u, grad_v, box, np.int64(slots[i]), us, vs)
        if not ok:
            continue
        nu = 0.0
        nv = 0.0
        if normal_only:
            # Along the edge the field shows only its events' scatter, not the edge's position.
            nu, nv = _projected_normal(tangents, i, R_cw, X, Y, Z, fx, fy)
            if nu != 0.0 or nv != 0.0:
                gn = fu * nu + fv * nv
                fu = gn * nu
                fv = gn * nv
        inside += 1
        rho, w = _rho_weight(f, loss, k)
        res[i] = f
        wts[i] = w
        cost += rho
        if f < inlier_thr:
            inl += 1
            swr2_in += w * f * f
        swr2 += w * f * f
        for a in range(6):
            J[a] = fu * Ju[a] + fv * Jv[a]
            b[a] += w * f * J[a]
        if not second_order:
            # Gauss-Newton: J^T W J.
            for a in range(6):
                wa = w * J[a]
                for c in range(a, 6):
                    H[a, c] += wa * J[c]
            continue
        # Newton on 0.5 f^2 in the image: A = grad f grad f^T + f * Hess f, clamped to PSD, so points
        # sitting on the TDF minimum (zero gradient) still hold the pose through the curvature.
        # From the field itself (the same values as its curvature images): the field need not build them.
        huu, huv, hvv = bilinear_curvature_from_value(value, box, np.int64(slots[i]), us, vs)
        if nu != 0.0 or nv != 0.0:
            hnn = nu * nu * huu + 2.0 * nu * nv * huv + nv * nv * hvv
            huu = hnn * nu * nu
            huv = hnn * nu * nv
            hvv = hnn * nv * nv
        a11 = fu * fu + f * huu
        a12 = fu * fv + f * huv
        a22 = fv * fv + f * hvv
        tr = 0.5 * (a11 + a22)
        det = a11 * a22 - a12 * a12
        disc = tr * tr - det
        if disc < 0.0:
            disc = 0.0
        sq = np.sqrt(disc)
        l1 = tr + sq
        l2 = tr - sq
        # Eigenvector of l1 (the other is orthogonal).
        if abs(a12) > 1e-12:
            e1u = l1 - a22
            e1v = a12
        elif a11 >= a22:
            e1u = 1.0
            e1v = 0.0
        else:
            e1u = 0.0
            e1v = 1.0
        nrm = np.sqrt(e1u * e1u + e1v * e1v)
        e1u /= nrm
        e1v /= nrm
        s1 = np.sqrt(l1) if l1 > 0.0 else 0.0
        s2 = np.sqrt(l2) if l2 > 0.0 else 0.0
        for a in range(6):
            Q1[a] = s1 * (e1u * Ju[a] + e1v * Jv[a])
            Q2[a] = s2 * (-e1v * Ju[a] + e1u * Jv[a])
        for a in range(6):
            q1 = w * Q1[a]
            q2 = w * Q2[a]
            for c in range(a, 6):
                H[a, c] += q1 * Q1[c] + q2 * Q2[c]
    for a in range(6):
        for c in range(a):
            H[a, c] = H[c, a]
    return cost, inside, inl, swr2, swr2_in


@nb.njit(cache=True)
def _damped_step(H, b, lam):
    """``-(H + lam diag(H + 1e-12))^-1 b`` for the 6x6 LM system by Gaussian elimination with partial pivoting
    (one compiled call instead of several small numpy ones per iteration); NaN if the system is singular."""
    n = 6
    A = np.empty((n, n + 1))
    for i in range(n):
        for j in range(n):
            A[i, j] = H[i, j]
        A[i, i] += lam * (H[i, i] + 1e-12)
        A[i, n] = -b[i]
    for c in range(n):
        p = c
        for r in range(c + 1, n):
            if abs(A[r, c]) > abs(A[p, c]):
                p = r
        if A[p, c] == 0.0:
            return np.full(n, np.nan)
        if p != c:
            for j in range(n + 1):
                A[c, j], A[p, j] = A[p, j], A[c, j]
        for r in range(c + 1, n):
            f = A[r, c] / A[c, c]
            for j in range(c, n + 1):
                A[r, j] -= f * A[c, j]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        acc = A[i, n]
        for j in range(i + 1, n):
            acc -= A[i, j] * x[j]
        x[i] = acc / A[i, i]
    return x


@nb.njit(cache=True)
def _linearise_at(points, slots, T_cw, fx, fy, cx, cy, value, grad_u, grad_v, box, second_order, loss, k, inlier_thr, H, b, res, wts, uv,
                  tangents, twist, lag_s, floor_px, extra, normal_only):
    """:func:`_linearise` at the (4, 4) ``T_cw`` as gtsam hands it out (any memory layout): its rotation and
    translation copied here, not by two ``np.ascontiguousarray`` calls per linearisation."""
    R = np.empty((3, 3))
    t = np.empty(3)
    for i in range(3):
        for j in range(3):
            R[i, j] = T_cw[i, j]
        t[i] = T_cw[i, 3]
    return _linearise(points, slots, R, t, fx, fy, cx, cy, value, grad_u, grad_v, box, second_order, loss, k, inlier_thr,
                      H, b, res, wts, uv, tangents, twist, lag_s, floor_px, extra, normal_only)


@nb.njit(cache=True)
def _lm_step(H, b, prior_H, prior_b, with_prior, lam):
    """(step, finite) of the damped system at the current linearisation, the prior's terms added when ``with_prior``
    (the same sums numpy forms, one compiled call instead of two additions, the solve and a finiteness test)."""
    if with_prior:
        step = _damped_step(H + prior_H, b + prior_b, lam)
    else:
        step = _damped_step(H, b, lam)
    for i in range(6):
        if not np.isfinite(step[i]):
            return step, False
    return step, True



@nb.njit(cache=True)
def _strided_kernel(values, out):
    """``out[i] = values[floor(i * (n / m))]`` for the m = ``out.shape[0]`` of n = ``values.shape[0]``: the evenly strided
    subset of :func:`~evpose.tracker.registration.subsample_indices` (the same float64 products and floors), gathered."""
    r = values.shape[0] / out.shape[0]
    for i in range(out.shape[0]):
        out[i] = values[np.int64(np.floor(i * r))]


@nb.njit(cache=True)
def _polarity_trail_kernel(polarity, off, on, both, out):
    """``out[i]`` = ``off`` / ``on`` / ``both`` for a negative / positive / zero ``polarity[i]``."""
    for i in range(polarity.shape[0]):
        p = polarity[i]
        out[i] = off if p < 0 else (on if p > 0 else both)

_NO_PRIOR_TERMS = (np.zeros((6, 6)), np.zeros(6))
"""Placeholders handed to :func:`_lm_step` when there is no prior (never read)."""


_NO_TANGENTS = np.zeros((0, 3))
_NO_TWIST = np.zeros(6)
_NO_EXTRA = np.zeros(0)
