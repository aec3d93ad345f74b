"""Event-map registration (STPE): robust Levenberg-Marquardt on SE(3) minimising the TDF at projected map points.

Residual per map point ``r_k = TDF(pi(T_cam_world p_k))`` (bilinear), Jacobian
``grad TDF(u) * d pi / dX * dX / d xi`` with the pose perturbed on the right,
``T_world_cam <- T_world_cam * Exp(xi)``, ``xi = (omega, v)`` in gtsam's Pose3
tangent order (rotation, translation). Then ``X' = X + [X]x omega - v``, so
``dr/domega = g x X`` and ``dr/dv = -g`` with ``g = dr/dX``.

IRLS: the robust weight multiplies residual *and* Jacobian (normal equations
``J^T W J xi = -J^T W r``), unlike ESVO which weights the residual only.
Covariance is ``(J^T W J)^-1 * sigma^2`` with the weighted residual variance.
All per-point work for one linearisation is one numba pass, and the damped 6x6
solve (prior added) another (:mod:`evpose.tracker.registration_kernels`); the whole LM loop, the SE(3) algebra
and the prior's terms included, is one compiled call (:mod:`evpose.tracker.field_lm_kernel`, session 43; before,
gtsam and numpy in Python, whose rounding the compiled loop matches only to ~1e-16). What a call cost besides its
points before that, from ``tracking.registration_cost`` (2 s landing, 346x260, load ~6):
25-65 us per call and 8-11 us per linearisation (57-90 and 12-17 before these
helpers), next to ~65-90 ns per point and linearisation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import gtsam
import numpy as np

from evpose.frontend.distance_field import TemporalDistanceField, polarity_slots
from evpose.tracker.registration_kernels import (  # noqa: F401 (_rho_weight, _linearise, _damped_step re-exported)
    _NO_EXTRA, _NO_PRIOR_TERMS, _NO_TANGENTS, _NO_TWIST, _damped_step, _linearise, _linearise_at, _lm_step, _rho_weight,
    _polarity_trail_kernel, _strided_kernel)
from evpose.tracker.registration_config import RegistrationConfig, ResidualVariance, RobustLoss  # noqa: F401 (re-exported)
from evpose.tracker.field_lm_kernel import DEGENERATE, NO_COVARIANCE, NO_WEIGHT, NON_FINITE, health_and_covariance, lm_loop

_EYE4, _ZERO6x6 = np.eye(4), np.zeros((6, 6))
_LOSS_ID = {RobustLoss.L2: 0, RobustLoss.HUBER: 1, RobustLoss.CAUCHY: 2, RobustLoss.TUKEY: 3}


@dataclass
class RegistrationResult:
    """Outcome of one registration."""

    T_world_cam: np.ndarray
    """Refined pose (4, 4); the initial pose if registration failed before moving."""
    success: bool
    reason: str
    """Why it failed, in plain words ('' on success)."""
    covariance: np.ndarray | None
    """(6, 6) body-frame covariance (rotation, translation), or None if the Hessian is singular."""
    iterations: int
    points_used: int
    """Points that projected inside the image at the final pose."""
    inliers: int
    cost: float
    """Final robust cost (sum of rho over points inside the image)."""
    residuals: np.ndarray
    """float32 (M,) final TDF value per input point (1 if outside the image)."""
    weights: np.ndarray
    """float32 (M,) final robust weight per input point (0 if outside)."""
    uv: np.ndarray
    """float32 (M, 2) final projections, ideal-pinhole pixels (NaN behind the camera)."""


def subsample_indices(n: int, max_points: int) -> np.ndarray:
    """Deterministic, evenly strided subset of ``range(n)`` of at most ``max_points`` indices."""
    if n <= max_points:
        return np.arange(n, dtype=np.int64)
    return np.floor(np.arange(max_points) * (n / max_points)).astype(np.int64)


def strided_subset(values: np.ndarray, max_points: int) -> np.ndarray:
    """``values[subsample_indices(values.size, max_points)]`` (int64 ``values``), in one compiled pass."""
    values = np.ascontiguousarray(values, dtype=np.int64)
    if values.shape[0] <= max_points:
        return values.copy()
    out = np.empty(int(max_points), dtype=np.int64)
    _strided_kernel(values, out)
    return out



def polarity_trail(polarity: np.ndarray, off: float, on: float, both: float) -> np.ndarray:
    """float64 per point: ``off`` where ``polarity`` < 0, ``on`` where > 0, ``both`` where 0 (the nested ``np.where``
    of the per-point trail, one compiled pass)."""
    p = np.ascontiguousarray(polarity)
    out = np.empty(p.shape[0])
    _polarity_trail_kernel(p, float(off), float(on), float(both), out)
    return out

_ISOTROPIC: dict[tuple, np.ndarray] = {}


def _isotropic_information(rotation_deg: float, translation_m: float, residual_sigma: float) -> np.ndarray:
    """Information of the config's isotropic pose prior (read-only), built once per setting: every update needs it."""
    key = (rotation_deg, translation_m, residual_sigma)
    info = _ISOTROPIC.get(key)
    if info is None:
        if len(_ISOTROPIC) > 16:
            _ISOTROPIC.clear()
        s_r = np.radians(rotation_deg)
        s_t = translation_m
        info = _ISOTROPIC[key] = np.diag([1 / s_r**2] * 3 + [1 / s_t**2] * 3) * residual_sigma**2
        info.setflags(write=False)
    return info


try:  # numpy's own LAPACK gufunc behind np.linalg.inv (the same call, the same bits)
    from numpy.linalg import _umath_linalg as _lapack

    def _inv(a: np.ndarray) -> np.ndarray:
        """``np.linalg.inv`` of a positive-definite float64 matrix (checked by the caller), without its wrapper."""
        return _lapack.inv(a, signature="d->d")
except (ImportError, AttributeError):  # another numpy layout: the public function
    _inv = np.linalg.inv


def _levenberg_marquardt(pts, slots, fld, pose, K, config, loss, k, thr, prior=None, floor=None, normal_tangents=None):
    """Robust LM on one field; returns (pose, cost, inside, inliers, [sum w r^2, its inlier part], H, residuals, weights, uv,
    iterations). ``floor`` = (tangents, twist, lag s, floor px, per-point extra px) for :func:`_floor_shift`, None = off.
    ``normal_tangents`` (M, 3): world edge directions along whose projected normals alone the field's gradient and
    curvature are taken, None = both image directions."""
    m = pts.shape[0]
    fx, fy, cx, cy = float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])
    value, grad_u, grad_v, box, second = fld.value, fld.grad_u, fld.grad_v, fld.box, bool(config.second_order)
    tangents, twist, lag_s, floor_px, extra = floor if floor is not None else (_NO_TANGENTS, _NO_TWIST, 0.0, 0.0, _NO_EXTRA)
    normal_only = normal_tangents is not None
    if normal_only:
        tangents = normal_tangents
    cur = (np.zeros((6, 6)), np.zeros(6), np.empty(m), np.empty(m), np.empty((m, 2)))
    trial = (np.zeros((6, 6)), np.zeros(6), np.empty(m), np.empty(m), np.empty((m, 2)))
    with_prior = prior is not None
    T = pose.matrix()
    R, t = T[:3, :3].copy(), T[:3, 3].copy()
    T_p, info = (prior[0].matrix(), prior[1]) if with_prior else (_EYE4, _NO_PRIOR_TERMS[0])
    cost, inside, inl, swr2, swr2_in, it, swapped = lm_loop(
        R, t, pts, slots, fx, fy, cx, cy, value, grad_u, grad_v, box, second, loss, k, thr, tangents, twist, lag_s, floor_px, extra,
        normal_only, with_prior, T_p[:3, :3], T_p[:3, 3], info, float(config.lm_lambda), float(config.lm_lambda_min),
        int(config.max_iterations), float(config.convergence_rotation_rad), float(config.convergence_translation_m),
        float(config.convergence_cost_ratio), cur, trial)
    if swapped:
        cur = trial
    T[:3, :3], T[:3, 3] = R, t
    return gtsam.Pose3(mat=T), cost, inside, inl, [swr2, swr2_in], cur[0] + info if with_prior else cur[0].copy(), cur[2], cur[3], cur[4], it


def register_to_map(
    field_: TemporalDistanceField | Sequence[TemporalDistanceField],
    points_world: np.ndarray,
    T_world_cam_init: np.ndarray,
    K: np.ndarray,
    config: RegistrationConfig,
    point_polarity: np.ndarray | None = None,
    T_world_cam_prior: np.ndarray | None = None,
    twist_per_s: np.ndarray | None = None,
    prior_information: np.ndarray | None = None,
    prior_residual_sigma: float | None = None,
    tangents_world: np.ndarray | None = None,
    trail_offsets_px: np.ndarray | None = None,
    normal_only: bool = False,
) -> RegistrationResult:
    """Refine ``T_world_cam_init`` so the map points ``points_world`` (M, 3) land on low TDF.

    ``field_`` is one field or a coarse-to-fine sequence (each level starts from the
    previous level's pose; the health checks and the covariance use the last).
    Fields must already be computed for the polarities ``point_polarity`` asks for
    (per point +1 / -1 / 0 = combined; None = combined for all). ``K`` is the ideal
    pinhole matrix the fields live in. ``T_world_cam_prior`` (default: the initial
    pose) is where the optional pose prior of ``config`` pulls.

    ``twist_per_s`` (6,) is the camera's body-frame velocity (rotation rad/s,
    translation m/s; right perturbation, gtsam order), e.g. ``Logmap(T_prev^-1
    T_pred) / dt`` of the motion model. With it the field's lag is compensated:
    the pose is registered ``config.field_lag_ms`` earlier (initial pose and prior
    moved back along the twist) and the result is moved forward again, so the
    returned pose belongs to the query time; without it the result trails a
    moving camera by that lag (about 1 px of image motion).

    ``prior_information`` (6, 6), if given, replaces the config's isotropic prior:
    the inverse covariance of the prior pose (body frame, rotation then
    translation), e.g. a motion filter's predicted covariance inverted; it is
    converted into the cost's units with ``prior_residual_sigma`` (TDF units;
    default ``config.prior_residual_sigma``, which also scales the config's
    isotropic prior). All zeros means no prior. With it, the returned covariance is that of the events
    alone (the prior's information taken out), for a caller that fuses the prior
    itself.

    ``tangents_world`` (M, 3): unit edge direction of each point (zero = unknown), which ``config.lag_floor_px``
    needs (with ``twist_per_s``); without them that floor is off. ``trail_offsets_px`` (M,): how much further
    each point's field is sampled behind it than the lag model says (negative: ahead), pixels, e.g. by the polarity
    it fires; it needs the tangents and the twist too. ``normal_only`` (needs the tangents) takes the field's
    gradient and curvature along each point's projected edge normal alone (see
    ``RegistrationConfig.normal_gradient_min_pixel_mrad``).
    """
    levels = [field_] if isinstance(field_, TemporalDistanceField) else list(field_)
    pts = np.ascontiguousarray(points_world, dtype=np.float64).reshape(-1, 3)
    m = pts.shape[0]
    slots = polarity_slots(point_polarity, m)
    loss = _LOSS_ID[RobustLoss(config.robust_loss)]
    k = float(config.robust_scale)
    thr = float(config.inlier_threshold)
    # ``mat=`` by name: pybind11 takes Pose3's matrix overload (its 5th) at once instead of trying the others (~1.7 us).
    pose = init = gtsam.Pose3(mat=np.asarray(T_world_cam_init, dtype=np.float64))
    lag = gtsam.Pose3()
    if twist_per_s is not None and config.field_lag_ms > 0:
        xi = np.asarray(twist_per_s, dtype=np.float64).reshape(6)
        if np.isfinite(xi).all():  # the method: np.all's Python wrapper costs more than the test
            lag = gtsam.Pose3.Expmap(xi * (float(config.field_lag_ms) * 1e-3))
    lag_inv = lag.inverse()
    pose = pose.compose(lag_inv)
    floor = None
    if (config.lag_floor_px > 0 or trail_offsets_px is not None) and tangents_world is not None and twist_per_s is not None and m:
        xi = np.ascontiguousarray(twist_per_s, dtype=np.float64).reshape(6)
        if np.isfinite(xi).all():
            extra = _NO_EXTRA if trail_offsets_px is None else np.ascontiguousarray(trail_offsets_px, dtype=np.float64).reshape(m)
            floor = (np.ascontiguousarray(tangents_world, dtype=np.float64).reshape(m, 3), xi,
                     float(config.field_lag_ms) * 1e-3, float(config.lag_floor_px), extra)
    normal_tangents = (np.ascontiguousarray(tangents_world, dtype=np.float64).reshape(m, 3)
                       if normal_only and tangents_world is not None and m else None)
    if m == 0 or not levels:
        z = np.zeros(0, np.float32)
        return RegistrationResult(pose.compose(lag).matrix(), False, "no map points to register", None, 0, 0, 0, 0.0, z, z, np.zeros((0, 2), np.float32))
    prior = None
    if prior_information is not None and not np.asarray(prior_information).any():
        pass  # an all-zero information matrix: no prior at all (the caller fuses the prediction itself)
    elif prior_information is not None:
        sig = float(config.prior_residual_sigma if prior_residual_sigma is None else prior_residual_sigma)
        info = 0.5 * (prior_information + prior_information.T) * sig**2
        T_p = init if T_world_cam_prior is None else gtsam.Pose3(np.asarray(T_world_cam_prior, dtype=np.float64))
        # The prior's covariance belongs to the query time; moved back by the lag it changes by Ad(lag).
        ad = lag_inv.AdjointMap()
        prior = (T_p.compose(lag_inv), ad.T @ info @ ad)
    elif config.prior_translation_m > 0 and config.prior_rotation_deg > 0:
        info = _isotropic_information(config.prior_rotation_deg, config.prior_translation_m, config.prior_residual_sigma)
        T_p = init if T_world_cam_prior is None else gtsam.Pose3(np.asarray(T_world_cam_prior, dtype=np.float64))
        prior = (T_p.compose(lag_inv), info)
    total_it = 0
    for fld in levels:
        pose, cost, inside, inl, swr2, H, res, wts, uv, it = _levenberg_marquardt(pts, slots, fld, pose, K, config, loss, k, thr, prior,
                                                                                  floor, normal_tangents)
        total_it += it

    def result(ok, reason, cov):
        # Back to the query time: the registered pose is the camera's ``field_lag_ms`` earlier.
        return RegistrationResult(pose.compose(lag).matrix(), ok, reason, cov, total_it, int(inside), int(inl), float(cost),
                                  res.astype(np.float32), wts.astype(np.float32), uv.astype(np.float32))

    # Health checks and covariance at the final pose.
    if inside < config.min_points:
        return result(False, f"only {inside} map points project into the image (need {config.min_points})", None)
    if inl < config.min_inlier_ratio * inside:
        return result(False, f"only {inl} of {inside} map points lie on recent events (TDF < {thr:g})", None)
    # Points reading TDF ~1 (their edge did not fire) add nothing to H but w r^2 ~ w each: counted in the residual
    # variance they inflate the covariance several times over (see ``ResidualVariance``).
    sigma2 = (swr2[1] if ResidualVariance(config.residual_variance) is ResidualVariance.INLIERS else swr2[0]) / max(inl - 6, 1)
    # With ``prior_information`` the caller fuses the prior itself (a motion filter): the covariance is the events' alone.
    # Moving the pose by ``lag`` (right) maps a body perturbation d to Ad(lag^-1) d.
    without_prior = prior is not None and prior_information is not None
    cov = np.empty((6, 6))
    status = health_and_covariance(H, float(config.max_condition), sigma2, without_prior, prior[1] if without_prior else _ZERO6x6,
                                   lag_inv.AdjointMap(), cov)
    if status == NON_FINITE:
        return result(False, "registration produced non-finite values", None)
    if status == DEGENERATE:
        return result(False, "degenerate geometry: the visible map does not constrain all 6 degrees of freedom", None)
    if status == NO_WEIGHT:
        # Every residual outside the loss's support (Tukey with a scale below the residuals: weight 0): H is the prior's
        # alone and the covariance would be 0, which made the fused modes raise "Singular matrix" (session 25).
        return result(False, f"no map point's residual lies within the {RobustLoss(config.robust_loss).value} loss's scale {k:g} (all weights 0)", None)
    return result(True, "", None if status == NO_COVARIANCE else cov)
