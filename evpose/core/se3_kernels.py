"""SE(3) algebra for the compiled registration loops: a pose is a rotation ``R`` (3, 3) and a translation ``t`` (3,),
tangent vectors are in gtsam's order (rotation, translation) with the right perturbation ``T Exp(xi)``.

The registrations' loops (:mod:`evpose.tracker.field_lm_kernel`, :mod:`evpose.tracker.event_gauss_newton`) step their pose
here instead of through gtsam's ``Pose3`` in Python (a Python round trip per step cost more than the step). The
formulas are gtsam's (``Pose3::Expmap`` / ``Logmap``: Rodrigues' rotation and the left Jacobian of SO(3) on the
translation, its inverse for the logarithm, series near zero angle) in a different summation order, so a pose
agrees with gtsam's to ~1e-16 relative, not bit for bit.
"""

from __future__ import annotations

import numba as nb
import numpy as np

_SERIES_BELOW = 1e-4
"""Squared angle below which the coefficients below are taken from their series (whose next terms are < 1e-20 there):
the closed forms of ``C`` and ``D`` cancel, losing ~eps / theta^2."""


@nb.njit(cache=True, inline="always")
def _coefficients(theta2):
    """(A, B, C) = (sin t / t, (1 - cos t) / t^2, (t - sin t) / t^3) of the angle ``t`` whose square is ``theta2``."""
    if theta2 < _SERIES_BELOW:
        a = 1.0 - theta2 / 6.0 * (1.0 - theta2 / 20.0 * (1.0 - theta2 / 42.0))
        b = 0.5 * (1.0 - theta2 / 12.0 * (1.0 - theta2 / 30.0 * (1.0 - theta2 / 56.0)))
        c = (1.0 - theta2 / 20.0 * (1.0 - theta2 / 42.0 * (1.0 - theta2 / 72.0))) / 6.0
        return a, b, c
    theta = np.sqrt(theta2)
    s = np.sin(theta)
    h = np.sin(0.5 * theta)
    a = s / theta
    return a, 2.0 * h * h / theta2, (1.0 - a) / theta2


@nb.njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@nb.njit(cache=True)
def se3_exp(xi, R, t):
    """``R``, ``t`` := ``Exp(xi)`` (``R = I + A W + B W^2``, ``t = v + B w x v + C w x (w x v)``)."""
    w0, w1, w2 = xi[0], xi[1], xi[2]
    v0, v1, v2 = xi[3], xi[4], xi[5]
    theta2 = w0 * w0 + w1 * w1 + w2 * w2
    a, b, c = _coefficients(theta2)
    # W^2 = w w^T - theta^2 I
    R[0, 0] = 1.0 + b * (w0 * w0 - theta2)
    R[1, 1] = 1.0 + b * (w1 * w1 - theta2)
    R[2, 2] = 1.0 + b * (w2 * w2 - theta2)
    R[0, 1] = -a * w2 + b * w0 * w1
    R[1, 0] = a * w2 + b * w0 * w1
    R[0, 2] = a * w1 + b * w0 * w2
    R[2, 0] = -a * w1 + b * w0 * w2
    R[1, 2] = -a * w0 + b * w1 * w2
    R[2, 1] = a * w0 + b * w1 * w2
    x0, x1, x2 = _cross(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = _cross(w0, w1, w2, x0, x1, x2)
    t[0] = v0 + b * x0 + c * y0
    t[1] = v1 + b * x1 + c * y1
    t[2] = v2 + b * x2 + c * y2


@nb.njit(cache=True)
def so3_log(R, out):
    """``out[:3]`` := ``Log(R)`` (gtsam's ``SO3::Logmap``: from the trace, its series near zero angle; near pi the
    axis from the symmetric part, the angle by ``atan2``)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    v0, v1, v2 = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]  # 2 sin(theta) n
    if tr + 1.0 < 1e-3:  # near pi: the axis from the symmetric part's column with the largest diagonal
        c = 0.5 * (tr - 1.0)
        k = 0 if R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2] else (1 if R[1, 1] >= R[2, 2] else 2)
        n0 = 0.5 * (R[0, k] + R[k, 0]) - (c if k == 0 else 0.0)
        n1 = 0.5 * (R[1, k] + R[k, 1]) - (c if k == 1 else 0.0)
        n2 = 0.5 * (R[2, k] + R[k, 2]) - (c if k == 2 else 0.0)
        s = np.arctan2(0.5 * np.sqrt(v0 * v0 + v1 * v1 + v2 * v2), c) / np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        if n0 * v0 + n1 * v1 + n2 * v2 < 0.0:
            s = -s
        out[0], out[1], out[2] = s * n0, s * n1, s * n2
        return
    tr_3 = tr - 3.0
    if tr_3 < -1e-6:
        theta = np.arccos(0.5 * (tr - 1.0))
        mag = theta / (2.0 * np.sin(theta))
    else:  # theta near 0: the series of theta / (2 sin theta) in the trace
        mag = 0.5 - tr_3 / 12.0 + tr_3 * tr_3 / 60.0
    out[0] = mag * v0
    out[1] = mag * v1
    out[2] = mag * v2


@nb.njit(cache=True)
def se3_log(R, t, out):
    """``out`` (6,) := ``Log((R, t))`` (the translation through the inverse left Jacobian,
    ``u = t - w x t / 2 + D w x (w x t)``, ``D = (1 - A / (2 B)) / theta^2``)."""
    so3_log(R, out)
    w0, w1, w2 = out[0], out[1], out[2]
    theta2 = w0 * w0 + w1 * w1 + w2 * w2
    if theta2 < _SERIES_BELOW:
        d = (1.0 + theta2 / 60.0 * (1.0 + theta2 / 42.0)) / 12.0
    else:
        a, b, _ = _coefficients(theta2)
        d = (1.0 - a / (2.0 * b)) / theta2
    x0, x1, x2 = _cross(w0, w1, w2, t[0], t[1], t[2])
    y0, y1, y2 = _cross(w0, w1, w2, x0, x1, x2)
    out[3] = t[0] - 0.5 * x0 + d * y0
    out[4] = t[1] - 0.5 * x1 + d * y1
    out[5] = t[2] - 0.5 * x2 + d * y2


@nb.njit(cache=True)
def compose_into(R1, t1, R2, t2, R, t):
    """``R``, ``t`` := ``(R1, t1) (R2, t2)`` (they may not alias the inputs)."""
    for i in range(3):
        for j in range(3):
            R[i, j] = R1[i, 0] * R2[0, j] + R1[i, 1] * R2[1, j] + R1[i, 2] * R2[2, j]
        t[i] = R1[i, 0] * t2[0] + R1[i, 1] * t2[1] + R1[i, 2] * t2[2] + t1[i]


@nb.njit(cache=True)
def between_log(Ra, ta, Rb, tb, out):
    """``out`` (6,) := ``Log((Ra, ta)^-1 (Rb, tb))`` (gtsam's ``a.logmap(b)``)."""
    R = np.empty((3, 3))
    t = np.empty(3)
    for i in range(3):
        for j in range(3):
            R[i, j] = Ra[0, i] * Rb[0, j] + Ra[1, i] * Rb[1, j] + Ra[2, i] * Rb[2, j]
        t[i] = Ra[0, i] * (tb[0] - ta[0]) + Ra[1, i] * (tb[1] - ta[1]) + Ra[2, i] * (tb[2] - ta[2])
    se3_log(R, t, out)


@nb.njit(cache=True)
def inverse_into(R, t, R_inv, t_inv):
    """``R_inv``, ``t_inv`` := ``(R, t)^-1`` = ``(R^T, -R^T t)`` (the camera-from-world of a world-from-camera pose)."""
    for i in range(3):
        for j in range(3):
            R_inv[i, j] = R[j, i]
        t_inv[i] = -(R[0, i] * t[0] + R[1, i] * t[1] + R[2, i] * t[2])


@nb.njit(cache=True)
def step_pose(R, t, delta):
    """``(R, t)`` := ``(R, t) Exp(delta)`` in place."""
    dR = np.empty((3, 3))
    dt = np.empty(3)
    se3_exp(delta, dR, dt)
    R0 = R.copy()
    t0 = t.copy()
    compose_into(R0, t0, dR, dt, R, t)
