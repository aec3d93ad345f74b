"""The field registration's pose combined with the events' by their informations (:mod:`evpose.tracker.event_registration`).

Session 43: compiled (:func:`_combine_kernel`, the inverses by Cholesky, the SE(3) algebra of
:mod:`evpose.core.se3_kernels`) instead of three gtsam poses, a ``logmap``, an ``Expmap``, three LAPACK inverses and
small numpy products in Python (~30 us per update at load ~8, now ~3); equal to that recipe (:func:`_combine_python`,
still taken when a covariance is not positive definite, where it raises on a singular field covariance as before) to
rounding.
"""

from __future__ import annotations

import gtsam
import numba as nb
import numpy as np

from evpose.core.lapack_calls import inv
from evpose.core.se3_kernels import between_log, compose_into, se3_exp
from evpose.core.spd_kernels import spd_inverse
from evpose.tracker.registration import _inv


def combine_poses(T_f: np.ndarray, cov_f: np.ndarray, T_e: np.ndarray, cov_e: np.ndarray, convex: bool = False):
    """(pose, covariance) of the field registration's pose ``T_f`` (covariance ``cov_f``, its tangent space, gtsam
    order) combined with the events' ``T_e`` (``cov_e``) by their informations, in ``T_f``'s tangent space. The
    covariance is the full combination's; the pose its information-weighted mean, or with ``convex`` each tangent
    component weighted by the two diagonal informations alone (between the two poses, never beyond: see
    ``EventRegistrationConfig.combine_convex``)."""
    T, P = np.empty((4, 4)), np.empty((6, 6))
    if _combine_kernel(np.asarray(T_f, np.float64), np.asarray(cov_f, np.float64), np.asarray(T_e, np.float64),
                       np.asarray(cov_e, np.float64), bool(convex), T, P):
        return T, P
    return _combine_python(T_f, cov_f, T_e, cov_e, convex)


@nb.njit(cache=True)
def _combine_kernel(T_f, cov_f, T_e, cov_e, convex, T, P):
    """:func:`combine_poses` into ``T`` (4, 4) and ``P`` (6, 6); False (both undefined) when ``cov_f``, ``cov_e`` or
    the informations' sum is not positive definite."""
    I_f = np.empty((6, 6))
    I_e = np.empty((6, 6))
    if not (spd_inverse(cov_f, I_f) and spd_inverse(cov_e, I_e) and spd_inverse(I_f + I_e, P)):
        return False
    e = np.empty(6)
    between_log(T_f[:3, :3], T_f[:3, 3], T_e[:3, :3], T_e[:3, 3], e)
    step = np.empty(6)
    if convex:
        for i in range(6):
            step[i] = I_e[i, i] / (I_f[i, i] + I_e[i, i]) * e[i]
    else:
        g = np.empty(6)
        for i in range(6):
            acc = 0.0
            for j in range(6):
                acc += I_e[i, j] * e[j]
            g[i] = acc
        for i in range(6):
            acc = 0.0
            for j in range(6):
                acc += P[i, j] * g[j]
            step[i] = acc
    dR = np.empty((3, 3))
    dt = np.empty(3)
    R = np.empty((3, 3))
    t = np.empty(3)
    se3_exp(step, dR, dt)
    compose_into(T_f[:3, :3], T_f[:3, 3], dR, dt, R, t)
    T[:] = 0.0
    T[:3, :3] = R
    T[:3, 3] = t
    T[3, 3] = 1.0
    return True


def _combine_python(T_f, cov_f, T_e, cov_e, convex):
    """:func:`combine_poses` by gtsam and LAPACK (the recipe before session 43)."""
    T_f = gtsam.Pose3(mat=T_f)  # by name: pybind11 takes the matrix overload at once
    e = T_f.logmap(gtsam.Pose3(mat=T_e))
    I_f = inv(cov_f)  # a singular one raises as np.linalg.inv
    I_e = _inv(cov_e)  # positive definite (checked by the caller), as the sum below
    P = _inv(I_f + I_e)
    if convex:
        d_f, d_e = I_f.diagonal(), I_e.diagonal()  # np.diag's own call, without its wrapper
        step = d_e / (d_f + d_e) * e
    else:
        step = P @ (I_e @ e)
    return T_f.compose(gtsam.Pose3.Expmap(step)).matrix(), 0.5 * (P + P.T)
