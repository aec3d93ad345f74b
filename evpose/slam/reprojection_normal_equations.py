"""Motion-only refinement of one camera pose: the Gauss-Newton normal equations of its Huber reprojection errors, a
step on the left, and the loop that adds a prior to them (:mod:`evpose.slam.gyro_prior`'s rotation prior,
:mod:`evpose.slam.pnp_motion_prior`'s pose prior)."""

from __future__ import annotations

from typing import Callable

import cv2
import numpy as np


def reprojection_normal_equations(T_cw: np.ndarray, X: np.ndarray, z_obs: np.ndarray, K: np.ndarray, huber_px: float,
                                  sigma_px: float = 1.0) -> tuple[np.ndarray, np.ndarray] | None:
    """``(H, g)`` (6x6, 6) of the reprojection errors of world points ``X`` (N, 3) observed at ``z_obs`` (N, 2) by
    a pinhole ``K`` at ``T_cw`` (camera from world), residuals divided by ``sigma_px``, each point's 2D error Huber
    weighted at ``huber_px`` (in sigmas). Perturbations act on the left (``T <- Exp(delta) T``, rotation first). None
    when fewer than 3 points lie in front of the camera."""
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
    z = Xc[:, 2]
    good = z > 1e-9
    if good.sum() < 3:
        return None
    Xc, zo, zz = Xc[good], z_obs[good], z[good]
    u = fx * Xc[:, 0] / zz + cx
    v = fy * Xc[:, 1] / zz + cy
    r = np.c_[u - zo[:, 0], v - zo[:, 1]] / sigma_px
    e = np.linalg.norm(r, axis=1)
    w = np.where(e <= huber_px, 1.0, huber_px / np.maximum(e, 1e-12))
    # d(u, v)/d(Xc), then d(Xc)/d(delta) = [-[Xc]x, I].
    Ju = np.zeros((len(Xc), 2, 3))
    Ju[:, 0, 0] = fx / zz
    Ju[:, 0, 2] = -fx * Xc[:, 0] / zz**2
    Ju[:, 1, 1] = fy / zz
    Ju[:, 1, 2] = -fy * Xc[:, 1] / zz**2
    skew = np.zeros((len(Xc), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2] = -Xc[:, 2], Xc[:, 1]
    skew[:, 1, 0], skew[:, 1, 2] = Xc[:, 2], -Xc[:, 0]
    skew[:, 2, 0], skew[:, 2, 1] = -Xc[:, 1], Xc[:, 0]
    dX = np.concatenate([-skew, np.broadcast_to(np.eye(3), skew.shape)], axis=2)
    J = np.einsum("nij,njk->nik", Ju, dX) / sigma_px
    H = np.einsum("n,nji,njk->ik", w, J, J)
    g = np.einsum("n,nji,nj->i", w, J, r)
    return H, g


def left_gauss_newton_step(T_cw: np.ndarray, H: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, bool] | None:
    """``(Exp(delta) T_cw, converged)`` for the step ``delta = -H^-1 g`` (rotation first; converged: the step is
    under 1e-9 in rad and map units, so further steps change nothing measurable); None when ``H`` is singular."""
    try:
        delta = -np.linalg.solve(H, g)
    except np.linalg.LinAlgError:
        return None
    dT = np.eye(4)
    dT[:3, :3] = cv2.Rodrigues(delta[:3].reshape(3, 1))[0]
    dT[:3, 3] = delta[3:]
    return dT @ T_cw, bool(np.linalg.norm(delta) < 1e-9)


def refine_with_prior(K: np.ndarray, X: np.ndarray, z_obs: np.ndarray, T_cw: np.ndarray,
                      add_prior: Callable[[np.ndarray, np.ndarray, np.ndarray], None], huber_px: float,
                      sigma_px: float = 1.0, iterations: int = 8) -> np.ndarray:
    """Gauss-Newton from ``T_cw`` on :func:`reprojection_normal_equations` plus a prior: ``add_prior(T, H, g)`` adds
    its terms to ``H`` and ``g`` in place at the current ``T``. Stops after ``iterations``, on convergence, on a
    singular system or with fewer than 3 points in front. Returns the refined ``T_cam_world`` (4, 4)."""
    T = np.array(T_cw, np.float64)
    for _ in range(iterations):
        normal = reprojection_normal_equations(T, X, z_obs, K, huber_px, sigma_px)
        if normal is None:
            break
        H, g = normal
        add_prior(T, H, g)
        step = left_gauss_newton_step(T, H, g)
        if step is None:
            break
        T, converged = step
        if converged:
            break
    return T
