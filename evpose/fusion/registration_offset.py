"""A slowly varying registration offset along the shift / tilt ridges, estimated in the factor graph
(``FusionConfig.registration_offset_tau_s``).

The registrations' error is not white: along the ridges where a shift across the optical axis and a tilt about the
perpendicular axis move the image alike it wanders slowly (session 33: +6.6 mm for the flight's first ~0.6 s), and
a white model lets the fused state follow it (and the gyroscope bias learn it). Here each registered state ``j`` gets
an offset ``O_j`` (a world-frame Pose3, gtsam key ``o``) and the registration measures the pose through it:

* ``BetweenFactorPose3(O_j, X_j, z_j)``: ``X_j = O_j z_j`` up to the registration's own (white) covariance, whose
  residual ``Log(z_j^-1 O_j^-1 X_j)`` is the plain pose prior's when ``O_j`` is the identity;
* a first-order Gauss-Markov chain on ``O``: ``o_j = rho o_i + w`` (``o = Log O``, ``rho = exp(-dt / tau)``,
  ``w`` white with ``q = (1 - rho^2) P``, ``P`` the stationary covariance), its whitened cost split exactly into
  built-in (serialisable) factors as ``RegistrationErrorModel.AR1_WHITENED`` splits its own: a between factor of
  covariance ``q / rho``, a prior of ``q / (1 - rho)^2`` on every state (``q / (1 - rho)`` on a chain's first) and,
  while ``O_j`` is the newest, one more of ``q / (rho (1 - rho))`` (removed when the next offset takes its place);
* ``P`` is confined to the ridges, where it takes a share of the registration's own variance (:func:`split_ridge`):
  with ``r = registration_offset_ratio`` the registration factor keeps ``1 / (1 + r)`` of the (scaled) covariance's
  part along the two largest eigen-directions of its correlation matrix
  (:data:`~evpose.fusion.startup.STARTUP_RIDGE_DIRECTIONS`, the directions ``registration_startup_s`` widens) and the
  offset gets ``r / (1 + r)`` of it, plus :data:`OFF_RIDGE_SHARE` of the whole covariance over ``1 + r`` (so it is
  positive definite), taken to the IMU frame and to the world frame of ``O`` by the adjoint of the predicted pose
  (``O = X Exp(eta) X^-1`` for an offset ``eta`` in the body frame). One registration alone thus weighs as much as
  without the offset; a run of them carries less about the ridge, as their errors there are correlated.

Only the factor graph models it (the EKF takes the registrations as white). A state without a registration gets no
offset; the chain carries on across such states while its last offset is still in the window (``rho`` from the time
between them), and starts again (stationary prior) otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from evpose.fusion.startup import STARTUP_RIDGE_DIRECTIONS
from evpose.fusion.state import adjoint

_X, _O = ord("x") << 56, ord("o") << 56
"""gtsam ``Symbol`` keys of state 0's pose and offset (``Symbol('o', j)`` is ``_O | j``)."""

OFF_RIDGE_SHARE = 1e-3
"""The offset's stationary covariance off the ridges, as a share of the registration covariance: small enough that the
offset lives on the ridges, large enough to keep its noise models well conditioned."""


def offset_key(j: int) -> int:
    return _O | int(j)


def ridge_part(cov: np.ndarray) -> np.ndarray:
    """The part of a (6, 6) covariance along its correlation matrix's :data:`STARTUP_RIDGE_DIRECTIONS` largest
    eigen-directions (unit-free: the eigen-decomposition of the correlation matrix, scaled back by the sigmas)."""
    c = 0.5 * (cov + cov.T)
    d = np.sqrt(np.diag(c))
    dd = np.outer(d, d)
    w, V = np.linalg.eigh(c / dd)
    V = V[:, -STARTUP_RIDGE_DIRECTIONS:]
    return ((V * w[-STARTUP_RIDGE_DIRECTIONS:]) @ V.T) * dd


def split_ridge(ratio: float, cov: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The registration covariance shared between its white part and the offset: ``(cov`` with its ridge part times
    ``1 / (1 + ratio)``, ``base / (1 + ratio))``, the second for :func:`stationary_covariance` (whose ``ratio`` times
    its ridge part is the offset's share, ``ratio / (1 + ratio)`` of the ridge variance). ``cov``: the covariance the
    registration factor would have (start-up widening included), ``base``: the same without the widening (camera
    frame, scaled)."""
    return cov + (1.0 / (1.0 + ratio) - 1.0) * ridge_part(cov), base / (1.0 + ratio)


def stationary_covariance(ratio: float, cov_cam: np.ndarray, extrinsic, T_world_imu: np.ndarray) -> np.ndarray:
    """Stationary covariance ``P`` of the world-frame offset ``Log O`` for a registration of (scaled, camera-frame)
    covariance ``cov_cam`` at the IMU pose ``T_world_imu``: ``ratio`` times its ridge part plus :data:`OFF_RIDGE_SHARE`
    of it (the ridges found in the camera frame, where the registration made them), carried to the IMU frame by the
    extrinsic (:class:`~evpose.fusion.state.Extrinsic`) and to the world frame by the pose's adjoint."""
    P = extrinsic.imu_covariance(ratio * ridge_part(cov_cam) + OFF_RIDGE_SHARE * cov_cam)
    A = adjoint(T_world_imu)
    P = A @ P @ A.T
    return 0.5 * (P + P.T)


class OffsetChain:
    """The offsets' bookkeeping in :class:`~evpose.fusion.factor_graph.FactorGraphFusion`: the last offset's state
    index and time (None: no chain)."""

    def __init__(self, last: tuple[int, int] | None = None):
        self.last = last

    def add(self, gtsam, config, smoother, graph, values, stamps, j: int, t_us: int, dt_s: float, z, noise,
            cov_cam: np.ndarray, extrinsic, T_pred_imu: np.ndarray) -> tuple[int, bool]:
        """Add state ``j``'s registration through its offset and the offset's Gauss-Markov factors to ``graph`` (the
        offset's initial value to ``values``, its stamp to ``stamps``). ``z``: the measured IMU pose (gtsam Pose3),
        ``noise``: the registration factor's noise model, ``cov_cam``: the (scaled, camera-frame) registration
        covariance before any start-up widening, ``dt_s``: the time since the previous state (a chain's first ``rho``).
        ``extrinsic``: the camera-IMU :class:`~evpose.fusion.state.Extrinsic`. Returns the position in ``graph`` of
        the newest offset's extra prior (to be removed at the next offset) and whether the chain carried on from the
        previous offset (False: it started)."""
        o = offset_key(j)
        graph.add(gtsam.BetweenFactorPose3(o, _X | j, z, noise))
        tau = float(config.registration_offset_tau_s)
        last = self.last
        # The previous offset is still in the window (the smoother keeps window_states states; one spare).
        chained = last is not None and j - last[0] < int(config.window_states) - 1
        rho = math.exp(-(t_us - last[1]) * 1e-6 / tau) if chained else math.exp(-dt_s / tau)
        q = (1.0 - rho * rho) * stationary_covariance(float(config.registration_offset_ratio), cov_cam, extrinsic, T_pred_imu)
        identity = gtsam.Pose3()
        if chained:
            p = offset_key(last[0])
            graph.add(gtsam.BetweenFactorPose3(p, o, identity, gtsam.noiseModel.Gaussian.Covariance(q / rho)))
            graph.add(gtsam.PriorFactorPose3(o, identity, gtsam.noiseModel.Gaussian.Covariance(q / (1.0 - rho) ** 2)))
            values.insert(o, pose3=smoother.calculateEstimatePose3(p))
        else:
            graph.add(gtsam.PriorFactorPose3(o, identity, gtsam.noiseModel.Gaussian.Covariance(q / (1.0 - rho))))
            values.insert(o, pose3=identity)
        graph.add(gtsam.PriorFactorPose3(o, identity, gtsam.noiseModel.Gaussian.Covariance(q / (rho * (1.0 - rho)))))
        stamps[o] = float(j)
        self.last = (int(j), int(t_us))
        return graph.size() - 1, chained

