"""Two-view relative pose with the rotation taken from the gyro: only the translation direction is estimated.

Why (E-I-C2 indoors, session 37, ``/tmp/s37/ei37``): the homography / essential decomposition of an indoor two-view
start is 0.6-36 deg off in rotation (:mod:`evpose.slam.initialization`), while the gyro integrated over the same
0.01-0.1 s is good to hundredths of a degree even with an unknown bias. ``InertialConfig.init_max_gyro_deg`` refuses
starts more than 3 deg off, which costs tracked time, and the accepted re-joins 1.5-2.9 deg off carried most of the
rotation RPE of indoor seeds 26 and 32 (``steperr.py``). With the rotation ``R`` known, the epipolar constraint
``f2 . (t x R f1) = 0`` is linear in ``t``: each match gives a row ``a = (R f1) x f2`` with ``a . t = 0``, two matches
fix ``t`` up to sign (``t = a_i x a_j``), so RANSAC over pairs is cheap and all-inlier least squares is the smallest
singular vector. A short Gauss-Newton then refines rotation and translation direction together on the Sampson
error, with the gyro rotation as a prior (``sigma_rad``), and cheirality picks the sign.

The two seeds that missed the rotation target with the guard alone (session 37, ``/tmp/s37/ei37``: ``diag26.py``,
``diagrj.py``, ``diagpos.py``, ``steperr.py`` on main's results ``rv``). Seed 26 (0.0252 deg/m): its first map
started at 0.018 s from a homography reporting 1.7 deg of parallax; with the gyro's rotation the same matches have
0.43 deg, and the map's BA shrank it about 25 times per keyframe over its first three keyframes (newest position 0.027
-> 0.001 -> 2e-5 units), so the coasting velocity was ~3e-5 units/s, each re-join's scale 2e-5 to 4e-7 of the
two-view map, and all of the IMU initialisation's attempts (1.21-3.0 s) solved a negative scale (-1e4 to -2e3);
its rotation error is the re-joins' decomposed rotations, 1.5 / 2.9 / 1.7 deg off at 0.88 / 1.34 / 1.93 s. Seed 32
(0.0144 deg/m): initialised only at 2.88 s; the re-joins at 1.49 s (1.5 deg off) and 1.93 s (3.0 deg) carry 93 % of
its rotation error by 2.0 s. With ``InertialConfig.init_gyro_two_view`` both meet both targets (26: 0.0052 m/m,
0.0015 deg/m, initialised at 1.46 s; 32: 0.0079, 0.0017); figures over all seeds there.
"""

from __future__ import annotations

import cv2
import numpy as np

from evpose.core.trajectory import skew
from evpose.slam.geometry import parallax_deg
from evpose.slam.init_parallax import bearings
from evpose.slam.initialization import TwoViewResult, _evaluate


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` over the last axis of broadcastable arrays, without its axis bookkeeping (a tenth of the time on
    the small arrays here)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def sampson_px(K: np.ndarray, R: np.ndarray, t: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Signed Sampson distance, pixels (N,), of matches ``p1 -> p2`` under ``x2 = R x1 + t`` (camera-1-from-camera-0)."""
    Ki = np.linalg.inv(K)
    F = Ki.T @ skew(t) @ R @ Ki
    x1 = np.c_[p1, np.ones(len(p1))]
    x2 = np.c_[p2, np.ones(len(p2))]
    l2 = x1 @ F.T
    l1 = x2 @ F
    return np.sum(x2 * l2, axis=1) / np.sqrt(np.maximum(l2[:, 0] ** 2 + l2[:, 1] ** 2 + l1[:, 0] ** 2 + l1[:, 1] ** 2, 1e-36))


def sampson_px2(K: np.ndarray, R: np.ndarray, t: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Squared Sampson distance, pixels^2 (N,) (:func:`sampson_px`)."""
    return sampson_px(K, R, t, p1, p2) ** 2


def _sampson_px2_many(K: np.ndarray, R: np.ndarray, T: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """:func:`sampson_px2` for every unit translation of ``T`` (H, 3) at once, (H, N)."""
    Ki = np.linalg.inv(K)
    y1 = (np.c_[p1, np.ones(len(p1))] @ Ki.T) @ R.T  # R f1, normalised coordinates
    x2 = np.c_[p2, np.ones(len(p2))]
    f2 = x2 @ Ki.T
    l2 = _cross(T[:, None, :], y1[None]) @ Ki  # F x1 = Ki^T (t x R f1), row vectors
    l1 = (_cross(f2[None], T[:, None, :]) @ R) @ Ki  # F^T x2 = Ki^T R^T (f2 x t)
    num = np.sum(x2[None] * l2, axis=2) ** 2
    return num / np.maximum(l2[..., 0] ** 2 + l2[..., 1] ** 2 + l1[..., 0] ** 2 + l1[..., 1] ** 2, 1e-36)


def translation_direction_ransac(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, R: np.ndarray, threshold_px: float,
                                 iterations: int = 200, seed: int = 0) -> tuple[np.ndarray, np.ndarray] | None:
    """Unit translation ``t`` (sign arbitrary) of ``x2 = R x1 + t`` for a known rotation ``R`` and the inlier mask, by
    RANSAC over pairs of matches then least squares on the inliers; None with fewer than 2 matches or no consistent pair."""
    p1 = np.asarray(p1, np.float64).reshape(-1, 2)
    p2 = np.asarray(p2, np.float64).reshape(-1, 2)
    n = len(p1)
    if n < 2:
        return None
    A = _cross(bearings(K, p1) @ R.T, bearings(K, p2))
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n, iterations)
    j = (i + 1 + rng.integers(0, n - 1, iterations)) % n  # a second, different match
    T = _cross(A[i], A[j])
    norms = np.linalg.norm(T, axis=1)
    T = T[norms > 1e-12] / norms[norms > 1e-12, None]
    if not len(T):
        return None
    thr2 = threshold_px**2
    counts = (_sampson_px2_many(K, R, T, p1, p2) < thr2).sum(axis=1)
    best = T[int(np.argmax(counts))]  # ties: the first drawn (deterministic)
    best_in = sampson_px2(K, R, best, p1, p2) < thr2
    if best_in.sum() < 2:
        return None
    for _ in range(2):  # least squares on the inliers, then the inliers of that
        t = np.linalg.svd(A[best_in])[2][-1]
        inl = sampson_px2(K, R, t, p1, p2) < thr2
        if inl.sum() < 2:
            break
        best, best_in = t, inl
    return best / np.linalg.norm(best), best_in


def _prior_residual(Ki: np.ndarray, f1: np.ndarray, f2: np.ndarray, x2: np.ndarray, R_gyro: np.ndarray, sigma_px: float,
                    sigma_rad: float):
    """Residual function of :func:`refine_with_gyro_prior` at parameters ``x`` (3 rotation increments on ``R_gyro``, 2
    direction increments along the basis ``B`` orthogonal to ``t0``): the matches' Sampson distances over ``sigma_px``,
    then the rotation's prior over ``sigma_rad``."""

    def residual(x, t0, B):
        R = cv2.Rodrigues(x[:3])[0] @ R_gyro
        tt = t0 + B @ x[3:]
        tt = tt / np.linalg.norm(tt)
        y1 = f1 @ R.T
        l2 = _cross(tt, y1) @ Ki  # F x1 as rows
        l1 = (_cross(f2, tt) @ R) @ Ki  # F^T x2 as rows
        d = np.sum(x2 * l2, axis=1) / np.sqrt(np.maximum(l2[:, 0] ** 2 + l2[:, 1] ** 2 + l1[:, 0] ** 2 + l1[:, 1] ** 2, 1e-36))
        return np.r_[d / sigma_px, x[:3] / sigma_rad]

    return residual


def _normalised(K: np.ndarray, p1: np.ndarray, p2: np.ndarray):
    Ki = np.linalg.inv(K)
    x1 = np.c_[np.asarray(p1, np.float64).reshape(-1, 2), np.ones(len(p1))]
    x2 = np.c_[np.asarray(p2, np.float64).reshape(-1, 2), np.ones(len(p2))]
    return Ki, x1 @ Ki.T, x2 @ Ki.T, x2


def _numeric_jacobian(residual, x: np.ndarray, t: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r0 = residual(x, t, B)
    eye = np.eye(len(x))
    return r0, np.stack([(residual(x + 1e-7 * eye[k], t, B) - r0) / 1e-7 for k in range(len(x))], axis=1)


def refine_with_gyro_prior(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, R_gyro: np.ndarray, t: np.ndarray,
                           sigma_px: float, sigma_rad: float, iterations: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """``(R, t)`` minimising the inliers' Sampson error over ``sigma_px`` plus the rotation's angle from ``R_gyro``
    over ``sigma_rad`` (Gauss-Newton, numeric Jacobian, 3 rotation + 2 direction parameters); ``t`` stays unit."""
    Ki, f1, f2, x2 = _normalised(K, p1, p2)
    residual = _prior_residual(Ki, f1, f2, x2, R_gyro, sigma_px, sigma_rad)
    t = np.asarray(t, np.float64) / np.linalg.norm(t)
    x = np.zeros(5)
    eye = np.eye(5)
    for _ in range(iterations):
        B = np.linalg.svd(t[None, :])[2][1:].T  # two directions orthogonal to t
        x[3:] = 0.0
        r0, J = _numeric_jacobian(residual, x, t, B)
        xn = x + np.linalg.solve(J.T @ J + 1e-9 * eye, -J.T @ r0)
        rn = residual(xn, t, B)
        if rn @ rn >= r0 @ r0:
            break
        x = xn
        t = t + B @ x[3:]
        t = t / np.linalg.norm(t)
    return cv2.Rodrigues(x[:3])[0] @ R_gyro, t


def translation_direction_std_deg(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, R: np.ndarray, t: np.ndarray,
                                  sigma_rad: float, min_matches: int = 30) -> float:
    """Standard deviation of the unit translation direction of ``x2 = R x1 + t`` (largest axis of its 2 x 2 covariance),
    degrees, from the inlier matches ``p1 -> p2`` and the rotation's gyro prior ``sigma_rad`` around ``R``: the
    Gauss-Newton information of :func:`refine_with_gyro_prior`'s residuals at ``(R, t)``, the rotation marginalised out.
    The pixel noise ``sigma`` is the matches' own RMS Sampson distance, so fewer than ``min_matches`` matches (whose
    RMS is itself too uncertain: 16 synthetic matches at 1 px claimed 2.5 deg for a direction 69 deg off) give
    infinity. The direction's rows of the information are built from the measured epipolar vectors ``a = R f1 x f2``,
    which carry the noise as well as the translation's flow: with no translation at all the noise alone would claim ``1 / sqrt(n)`` radians. That
    noise part is taken out: per match, its expected contribution ``sigma^2 (P b_k . P b_l) / |P t|^2`` (``P`` the
    projection orthogonal to ``R f1``, ``b_k`` the direction increments; the Sampson distance and the direction's
    derivative see the same noise vector in the plane orthogonal to ``R f1``). Infinite when what is left does not
    determine the direction (a pure rotation). ``InertialConfig.init_gyro_two_view_max_direction_std_deg``."""
    p1 = np.asarray(p1, np.float64).reshape(-1, 2)
    p2 = np.asarray(p2, np.float64).reshape(-1, 2)
    n = len(p1)
    if n < max(min_matches, 3):
        return float("inf")
    t = np.asarray(t, np.float64) / np.linalg.norm(t)
    rms = float(np.sqrt(np.mean(sampson_px2(K, R, t, p1, p2))))
    sigma_px = max(rms * np.sqrt(n / (n - 2)), 1e-9)  # 2 direction parameters fitted to the matches
    Ki, f1, f2, x2 = _normalised(K, p1, p2)
    residual = _prior_residual(Ki, f1, f2, x2, R, 1.0, 1.0)  # pixels; the prior is added below
    B = np.linalg.svd(t[None, :])[2][1:].T
    _, J = _numeric_jacobian(residual, np.zeros(5), t, B)
    J = J[:n]
    u = f1 @ R.T
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    Pb = B.T[None, :, :] - (u @ B)[:, :, None] * u[:, None, :]  # (n, 2, 3): P_i b_k
    Pt = t[None, :] - (u @ t)[:, None] * u
    noise = np.einsum("nki,nli->kl", Pb, Pb / np.maximum(np.sum(Pt * Pt, axis=1), 1e-12)[:, None, None])
    info = J.T @ J / sigma_px**2
    info[3:, 3:] -= noise  # (sigma^2 noise) / sigma^2
    info[:3, :3] += np.eye(3) / sigma_rad**2
    if np.linalg.eigvalsh(0.5 * (info[3:, 3:] + info[3:, 3:].T))[0] <= 0:
        return float("inf")
    try:
        cov = np.linalg.inv(info)[3:, 3:]
    except np.linalg.LinAlgError:
        return float("inf")
    ev = np.linalg.eigvalsh(0.5 * (cov + cov.T))
    if not np.isfinite(ev).all() or ev[0] <= 0:
        return float("inf")
    return float(np.degrees(np.sqrt(ev[-1])))


def two_view_with_rotation(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, R_c0_c1: np.ndarray, cfg, seed: int = 0,
                           sigma_deg: float = 0.1, model: str = "gyro", min_parallax_deg: float | None = None,
                           max_direction_std_deg: float = 0.0) -> TwoViewResult:
    """A two-view start from matched pixels with camera 1's orientation in camera 0's frame ``R_c0_c1`` from the gyro:
    the translation direction by :func:`translation_direction_ransac`, both refined by :func:`refine_with_gyro_prior`
    (prior ``sigma_deg``), the sign by cheirality; then the checks and the unit median depth of
    :func:`evpose.slam.initialization.initialize_two_view` (``min_triangulated``, and ``min_parallax_deg``, that of
    ``cfg`` when None). ``max_direction_std_deg`` > 0: a start under the parallax bar is taken when its translation
    direction's standard deviation is at most this (:func:`translation_direction_std_deg`,
    ``InertialConfig.init_gyro_two_view_max_direction_std_deg``)."""
    min_par = cfg.min_parallax_deg if min_parallax_deg is None else min_parallax_deg
    p1 = np.asarray(p1, np.float64).reshape(-1, 2)
    p2 = np.asarray(p2, np.float64).reshape(-1, 2)
    R_g = np.asarray(R_c0_c1, np.float64).T  # x2 = R x1 + t
    found = translation_direction_ransac(K, p1, p2, R_g, cfg.ransac_threshold_px, seed=seed)
    if found is None:
        return TwoViewResult(False, "no translation direction fits the gyro's rotation", model=model)
    t, inl = found
    R, t = refine_with_gyro_prior(K, p1[inl], p2[inl], R_g, t, max(cfg.ransac_threshold_px, 1.0), np.radians(sigma_deg))
    n_good, good, X, T_wc2 = max((_evaluate(K, R, sg * t, p1, p2, cfg) for sg in (1.0, -1.0)), key=lambda c: c[0])
    if n_good < cfg.min_triangulated:
        return TwoViewResult(False, f"{n_good} triangulated points < {cfg.min_triangulated} ({model})", model=model)
    par = float(np.median(parallax_deg(np.eye(4), T_wc2, X[good])))
    std = float("nan")
    if par < min_par:
        if max_direction_std_deg > 0:
            # Under the bar the translation's uncertainty decides: many well-spread matches can pin a low-parallax pair.
            std = translation_direction_std_deg(K, p1[inl], p2[inl], R, t, np.radians(sigma_deg))
        if not std <= max_direction_std_deg:
            more = f", translation direction std {std:.2f} deg > {max_direction_std_deg}" if max_direction_std_deg > 0 else ""
            return TwoViewResult(False, f"median parallax {par:.2f} deg < {min_par} ({model}{more})", model=model, median_parallax_deg=par,
                                 direction_std_deg=std)
    scale = float(np.median(X[good, 2]))
    X = X / scale
    T_wc2 = T_wc2.copy()
    T_wc2[:3, 3] /= scale
    X[~good] = np.nan
    return TwoViewResult(True, "", T_wc2, X, good, model, 0.0, par, std)
