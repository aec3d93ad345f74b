"""Baseline test of two-view initialisation that needs no decomposition: the parallax left after the best pure rotation.

A homography or essential matrix decomposed from tracks with almost no baseline
(a camera turning fast at a few millimetres of translation per MCI) still
"triangulates" points in front of both views, and its decomposed translation
is arbitrary, so the triangulation angle it reports says nothing. The rotation
that best maps the first view's bearings onto the second's (orthogonal
Procrustes) explains all the flow of a pure rotation; what it leaves is the
flow only translation makes, and its median angle bounds the real parallax.
"""

from __future__ import annotations

import numpy as np


def bearings(K: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Unit viewing rays (N, 3) of ideal-pinhole pixels ``uv`` (N, 2)."""
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    b = np.c_[(uv[:, 0] - K[0, 2]) / K[0, 0], (uv[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(uv))]
    return b / np.linalg.norm(b, axis=1, keepdims=True)


def best_rotation(b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """Rotation ``R`` minimising ``sum |b2 - R b1|^2`` over unit rays (Kabsch), (3, 3)."""
    U, _, Vt = np.linalg.svd(b2.T @ b1)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    return U @ D @ Vt


def rotation_compensated_parallax_deg(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, trim: float = 0.8) -> float:
    """Median angle between the second view's rays and the first view's rays rotated by the best pure rotation, degrees.

    The rotation is fitted twice, the second time to the ``trim`` share of matches it explained best (a few bad tracks
    must not tilt it). NaN with fewer than three matches.
    """
    b1, b2 = bearings(K, p1), bearings(K, p2)
    if len(b1) < 3:
        return float("nan")
    R = best_rotation(b1, b2)
    res = _angles(b2, b1 @ R.T)
    keep = res <= np.quantile(res, trim)
    if keep.sum() >= 3:
        R = best_rotation(b1[keep], b2[keep])
        res = _angles(b2, b1 @ R.T)
    return float(np.degrees(np.median(res)))


def _angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # atan2 of cross and dot: accurate for the sub-degree angles this test is about (arccos is not).
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.sum(a * b, axis=1))


def rotation_fit_disagreement_deg(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, T_wc2: np.ndarray) -> float:
    """Angle between the rotation of a two-view solution (``T_wc2``, first view at the origin) and the pure rotation
    fitted to the rays, degrees. Over a short baseline the fit is close to the true rotation (translation adds flow of
    the order of the parallax); a decomposition that turns the camera by degrees more than the rays do is wrong."""
    R_fit = best_rotation(bearings(K, p1), bearings(K, p2))
    R_21 = np.asarray(T_wc2)[:3, :3].T
    c = (np.trace(R_fit.T @ R_21) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def relative_pose_near_rotation_fit(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, threshold_px: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Relative pose ``(R, t)`` (``x2 = R x1 + t``, unit ``t``) at the epipolar-error minimum nearest the pure-rotation fit.

    A decomposed essential matrix or homography is the global minimum of its RANSAC model, which over a few
    millimetres of baseline the noise decides; the true motion is then a local minimum next to the rotation the rays
    imply. Started at that rotation (translation: the direction best orthogonal to every ``R b1 x b2``), a robust
    Gauss-Newton over rotation and translation direction (Sampson error in pixels, Huber at ``threshold_px``) stays in
    that basin. Both translation signs are tried by the caller's cheirality count. None with fewer than five matches.
    """
    from scipy.optimize import least_squares
    from scipy.spatial.transform import Rotation

    b1, b2 = bearings(K, p1), bearings(K, p2)
    if len(b1) < 5:
        return None
    R0 = best_rotation(b1, b2)
    n = np.cross(b1 @ R0.T, b2)
    t0 = np.linalg.svd(n)[2][-1]
    x1 = np.c_[(np.asarray(p1, float) - K[:2, 2]) / np.diag(K)[:2], np.ones(len(b1))]
    x2 = np.c_[(np.asarray(p2, float) - K[:2, 2]) / np.diag(K)[:2], np.ones(len(b1))]
    f = float(K[0, 0])

    def residuals(z):
        R = Rotation.from_rotvec(z[:3]).as_matrix() @ R0
        t = z[3:] / max(np.linalg.norm(z[3:]), 1e-12)
        tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
        E = tx @ R
        Ex1, Etx2 = x1 @ E.T, x2 @ E
        num = np.sum(x2 * Ex1, axis=1)
        den = Ex1[:, 0] ** 2 + Ex1[:, 1] ** 2 + Etx2[:, 0] ** 2 + Etx2[:, 1] ** 2
        # Sampson distance in pixels, plus a weak pull keeping |t| = 1 (the residual only sees its direction).
        return np.r_[f * num / np.sqrt(np.maximum(den, 1e-18)), 1e-3 * (np.linalg.norm(z[3:]) - 1.0)]

    sol = least_squares(residuals, np.r_[np.zeros(3), t0], loss="huber", f_scale=threshold_px, max_nfev=50)
    R = Rotation.from_rotvec(sol.x[:3]).as_matrix() @ R0
    t = sol.x[3:] / max(np.linalg.norm(sol.x[3:]), 1e-12)
    return R, t
