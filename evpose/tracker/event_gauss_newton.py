"""The event registration's Gauss-Newton passes (:mod:`evpose.tracker.event_registration`) as one compiled call.

Each step of that loop was a numba pass over the events plus ~15 small Python, numpy and gtsam calls (the pose's
matrix, the camera-from-world rotation, the prior's residual, the damped solve, ``Exp`` and ``compose``), which cost
about what the pass itself does. Here the passes, the prior's terms, the solve and the pose's step run in one call,
the SE(3) algebra in :mod:`evpose.core.se3_kernels`: the poses agree with the Python loop's to rounding (~1e-16
relative per step), not bit for bit. The Python loop (:func:`passes_python`) stays for the per-edge terms
(``edge_clusters``), whose weights it updates between passes.

Both take (iterations, min_events, T (4, 4) world-from-camera start, prior (T_prior, information) or None, the
:class:`~evpose.tracker.edge_clusters.EdgeTerms`, then :func:`_linearise_events`'s arguments from ``n_events`` to
``t_ref`` without ``R_cw``, ``t_cw``, and its last twelve as ``args``) and return
(pose (4, 4), events used, sum of w r^2, R_cw, t_cw at that pose), or None when a pass has too few events or a step
is not finite; ``H``, ``b``, ``sw``, ``swr`` of ``args`` then hold the last pass's sums.
"""

from __future__ import annotations

import gtsam
import numba as nb
import numpy as np

from evpose.tracker.event_registration_kernels import _linearise_events
from evpose.tracker.registration_kernels import _damped_step, _lm_step
from evpose.core.se3_kernels import inverse_into, step_pose
from evpose.tracker.field_lm_kernel import prior_cost_gradient

_EYE4 = np.eye(4)
_ZERO6x6 = np.zeros((6, 6))


@nb.njit(cache=True)
def gauss_newton_passes(iterations, min_events, R, t, with_prior, R_p, t_p, info, n, ex, ey, et, ep, assoc, pts, tg, fx, fy, cx,
                        cy, twist, t_ref, on_lead, off_lead, eg, burst, huber, gate, H, b, sw, swr, swj, pscale, R_cw, t_cw):
    """``iterations`` undamped Gauss-Newton steps of the world-from-camera pose (``R``, ``t``, updated in place) on
    the events' normal equations (:func:`_linearise_events`'s arguments), the prior ``info`` (6, 6) towards
    (``R_p``, ``t_p``) added when ``with_prior``, then a last pass at the final pose that leaves ``H``, ``b``, ``sw``,
    ``swr`` there and its camera-from-world pose in ``R_cw``, ``t_cw``. Returns (ok, events used, sum of w r^2):
    not ok when a pass uses fewer than ``min_events`` events or a step is not finite (the pose is then undefined)."""
    e = np.empty(6)
    g = np.empty(6)
    Hp = np.empty((6, 6))
    bp = np.empty(6)
    for it in range(iterations + 1):
        inverse_into(R, t, R_cw, t_cw)
        _, n_used, swr2 = _linearise_events(n, ex, ey, et, ep, assoc, pts, tg, R_cw, t_cw, fx, fy, cx, cy, twist, t_ref, on_lead,
                                            off_lead, eg, burst, huber, gate, H, b, sw, swr, swj, pscale)
        if n_used < min_events:
            return False, n_used, swr2
        if it == iterations:
            return True, n_used, swr2
        if with_prior:  # H + info, b + info Log(T_p^-1 T)
            prior_cost_gradient(R, t, R_p, t_p, info, e, g)
            for r in range(6):
                for c in range(6):
                    Hp[r, c] = H[r, c] + info[r, c]
                bp[r] = b[r] + g[r]
            delta = _damped_step(Hp, bp, 0.0)
        else:
            delta = _damped_step(H, b, 0.0)
        for r in range(6):
            if not np.isfinite(delta[r]):
                return False, n_used, swr2
        step_pose(R, t, delta)
    return True, 0, 0.0  # not reached: the last pass returns


def passes_compiled(iterations, min_events, T, prior, edges, n, ex, ey, et, ep, assoc, pts, tg, fx, fy, cx, cy, xi, t_ref, args):
    """The passes in one call of :func:`gauss_newton_passes` (``edges`` unused: they must be off)."""
    R, t = np.array(T[:3, :3]), np.array(T[:3, 3])
    R_cw, t_cw = np.empty((3, 3)), np.empty(3)
    T_p, info = (np.asarray(prior[0], np.float64), prior[1]) if prior is not None else (_EYE4, _ZERO6x6)
    ok, n_used, swr2 = gauss_newton_passes(iterations, min_events, R, t, prior is not None, T_p[:3, :3], T_p[:3, 3], info, n, ex, ey,
                                           et, ep, assoc, pts, tg, fx, fy, cx, cy, xi, t_ref, *args, R_cw, t_cw)
    if not ok:
        return None
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, t
    return pose, n_used, swr2, R_cw, t_cw


def passes_python(iterations, min_events, T, prior, edges, n, ex, ey, et, ep, assoc, pts, tg, fx, fy, cx, cy, xi, t_ref, args):
    """The passes as a Python loop over gtsam poses, with ``edges``' per-edge terms after each pass."""
    H, b, sw, swr = args[6:10]
    pose = gtsam.Pose3(mat=T)  # by name: pybind11 takes the matrix overload at once (the 5th of 5, ~1.7 us less)
    if prior is not None:
        T_p, info = gtsam.Pose3(mat=prior[0]), prior[1]
    for it in range(iterations + 1):
        mat = pose.matrix()
        R_cw = np.ascontiguousarray(mat[:3, :3].T)
        t_cw = -R_cw @ mat[:3, 3]
        _, n_used, swr2 = _linearise_events(n, ex, ey, et, ep, assoc, pts, tg, R_cw, t_cw, fx, fy, cx, cy, xi, t_ref, *args)
        if n_used < min_events:
            return None
        edges.after_pass(it == iterations, sw, swr, H, b)
        if it == iterations:
            break  # the last pass measures the covariance and the points' distances at the final pose
        if prior is not None:  # H + info, b + info e, the damped solve and its finiteness test in one call
            delta, finite = _lm_step(H, b, info, info @ T_p.logmap(pose), True, 0.0)
        else:
            delta, finite = _lm_step(H, b, H, b, False, 0.0)
        if not finite:
            return None
        pose = pose.compose(gtsam.Pose3.Expmap(delta))
    return pose.matrix(), n_used, swr2, R_cw, t_cw
