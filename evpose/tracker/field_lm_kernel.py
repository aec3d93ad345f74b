"""The field registration's Levenberg-Marquardt loop (:func:`evpose.tracker.registration._levenberg_marquardt`) as
one compiled call.

Each iteration was two numba calls (the damped solve and a 26-argument linearisation, ~4 us of dispatch each) and
~10 gtsam / numpy calls in Python (``Exp``, ``compose``, ``inverse().matrix()``, the prior's ``logmap`` and its two
products, the step's norms). Here the linearisations, the prior's terms, the damping and the acceptance test run in
one call, the SE(3) algebra in :mod:`evpose.core.se3_kernels`: the same algorithm, its poses equal to the Python
loop's to rounding (~1e-16 relative per step), not bit for bit (an acceptance test on the edge may then go the
other way). :func:`health_and_covariance` does the final checks and the covariance alike (Jacobi eigenvalues and a
Cholesky inverse, :mod:`evpose.core.spd_kernels`, instead of ~12 numpy / LAPACK calls).

Measured (session 43, ``/tmp/s43/lm43``; 346x260 2 s landing seed 0, main 29e1c44 against these kernels with the
event registration's and the read-out's, two sessions stepped alternately in one process, 1181 updates, load ~5):
CPU per update 3.540 -> 3.316 ms median (paired -0.214 +- 0.008 ms), p99 5.35 -> 4.87; the registration stage -0.188
ms (the field's -0.092, the events' -0.096), the fusion's read-out -0.021. Every issue-7 set's ATE the same to
1e-10 mm, poses within 5e-13 m of main's.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.tracker.registration_kernels import _damped_step, _linearise
from evpose.core.se3_kernels import between_log, compose_into, inverse_into, se3_exp
from evpose.core.spd_kernels import spd_inverse, sym_eigenvalues


@nb.njit(cache=True, inline="always")
def prior_cost_gradient(R, t, R_p, t_p, info, e, g):
    """0.5 e^T info e of ``e = Log(T_p^-1 T)``, with ``g`` := info e (the pose prior's cost and gradient)."""
    between_log(R_p, t_p, R, t, e)
    cost = 0.0
    for r in range(6):
        acc = 0.0
        for c in range(6):
            acc += info[r, c] * e[c]
        g[r] = acc
        cost += e[r] * acc
    return 0.5 * cost


@nb.njit(cache=True)
def lm_loop(R, t, pts, slots, fx, fy, cx, cy, value, grad_u, grad_v, box, second, loss, k, thr, tangents, twist, lag_s, floor_px, extra,
            normal_only, with_prior, R_p, t_p, info, lam, min_lam, max_iterations, conv_rot, conv_trans, conv_ratio, cur, trial):
    """Robust LM from the world-from-camera pose (``R``, ``t``, updated in place to the accepted pose) on one field
    (:func:`_linearise`'s arguments), the prior ``info`` towards (``R_p``, ``t_p``) added when ``with_prior``, damping
    ``lam`` (x 0.3 down to ``min_lam`` on an accepted step, x 10 on a rejected one, stop above 1e6), at most
    ``max_iterations`` steps, stopping when an accepted step moves less than ``conv_rot`` rad and ``conv_trans`` m or
    lowers the mean cost by less than ``conv_ratio`` of it. ``cur`` and ``trial`` are two sets of (H, b, res, wts,
    uv) buffers. Returns (cost, inside, inliers, sum w r^2, its inlier part, iterations, whether ``trial`` holds the
    accepted pose's linearisation)."""
    R_cw = np.empty((3, 3))
    t_cw = np.empty(3)
    Rc = np.empty((3, 3))
    tc = np.empty(3)
    dR = np.empty((3, 3))
    dt = np.empty(3)
    e = np.empty(6)
    pg = np.zeros(6)
    c_pg = np.zeros(6)
    Hp = np.empty((6, 6))
    bp = np.empty(6)
    inverse_into(R, t, R_cw, t_cw)
    cost, inside, inl, swr2, swr2_in = _linearise(pts, slots, R_cw, t_cw, fx, fy, cx, cy, value, grad_u, grad_v, box, second, loss, k, thr,
                                                  cur[0], cur[1], cur[2], cur[3], cur[4], tangents, twist, lag_s, floor_px, extra,
                                                  normal_only)
    pc = prior_cost_gradient(R, t, R_p, t_p, info, e, pg) if with_prior else 0.0
    swapped = False
    it = 0
    for it in range(1, max_iterations + 1):
        if inside < 6:
            break
        H, b = cur[0], cur[1]
        if with_prior:
            for r in range(6):
                for c in range(6):
                    Hp[r, c] = H[r, c] + info[r, c]
                bp[r] = b[r] + pg[r]
            delta = _damped_step(Hp, bp, lam)
        else:
            delta = _damped_step(H, b, lam)
        finite = True
        for r in range(6):
            finite = finite and np.isfinite(delta[r])
        if not finite:
            break  # singular (NaN) or overflowing system
        se3_exp(delta, dR, dt)
        compose_into(R, t, dR, dt, Rc, tc)
        inverse_into(Rc, tc, R_cw, t_cw)
        c_cost, c_inside, c_inl, c_swr2, c_swr2_in = _linearise(pts, slots, R_cw, t_cw, fx, fy, cx, cy, value, grad_u, grad_v, box, second,
                                                                loss, k, thr, trial[0], trial[1], trial[2], trial[3], trial[4], tangents,
                                                                twist, lag_s, floor_px, extra, normal_only)
        c_pc = prior_cost_gradient(Rc, tc, R_p, t_p, info, e, c_pg) if with_prior else 0.0
        # Compare mean cost: the set of points inside the image may change with the pose.
        old_mean = (cost + pc) / max(inside, 1)
        new_mean = (c_cost + c_pc) / c_inside if c_inside > 0 else np.inf
        if c_inside >= 6 and new_mean <= old_mean:
            R[:, :] = Rc
            t[:] = tc
            cost, inside, inl, swr2, swr2_in = c_cost, c_inside, c_inl, c_swr2, c_swr2_in
            pc = c_pc
            pg[:] = c_pg
            cur, trial = trial, cur
            swapped = not swapped
            lam = max(lam * 0.3, min_lam)
            small = (np.sqrt(delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]) < conv_rot
                     and np.sqrt(delta[3] * delta[3] + delta[4] * delta[4] + delta[5] * delta[5]) < conv_trans)
            if small or old_mean - new_mean < conv_ratio * old_mean:
                break
        else:
            lam = lam * 10.0 if lam > 0 else 1e-4
            if lam > 1e6:
                break
    return cost, inside, inl, swr2, swr2_in, it, swapped


OK, NON_FINITE, DEGENERATE, NO_WEIGHT, NO_COVARIANCE = 0, 1, 2, 3, 4
""":func:`health_and_covariance`'s outcomes: covariance written; ``H`` not finite; not all 6 degrees of freedom
constrained; the residual variance not > 0; success without a covariance (the caller's prior taken out leaves
``H`` not positive definite)."""


@nb.njit(cache=True)
def health_and_covariance(H, max_condition, sigma2, without_prior, prior_info, ad, cov):
    """The registration's final checks on its normal matrix ``H`` (prior included) and its covariance ``ad (H -
    [prior_info if without_prior]) ^-1 ad^T sigma2`` into ``cov`` (exactly symmetric): one of the outcomes above.
    Degenerate: the diagonally normalised ``H`` not positive definite or conditioned worse than ``max_condition``."""
    for i in range(6):
        for j in range(6):
            if not np.isfinite(H[i, j]):
                return NON_FINITE
    d = np.empty(6)
    for i in range(6):
        d[i] = np.sqrt(max(H[i, i], 1e-300))
    Hn = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            Hn[i, j] = H[i, j] / (d[i] * d[j])
    w = np.empty(6)
    sym_eigenvalues(Hn, w)
    if not w[0] > 0 or w[5] / w[0] > max_condition:  # not > 0: also NaN
        return DEGENERATE
    if not sigma2 > 0:
        return NO_WEIGHT
    C = np.empty((6, 6))
    if not spd_inverse(H - prior_info if without_prior else H, C):
        return NO_COVARIANCE if without_prior else DEGENERATE
    A = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for k in range(6):
                acc += ad[i, k] * C[k, j]
            A[i, j] = acc * sigma2
    for i in range(6):
        for j in range(i, 6):  # the upper triangle, mirrored: exactly symmetric
            acc = 0.0
            for k in range(6):
                acc += A[i, k] * ad[j, k]
            cov[i, j] = acc
            cov[j, i] = acc
    return OK
