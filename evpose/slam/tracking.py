"""Local-map tracking: the camera pose minimising the reprojection error of tracked map points (PnP RANSAC + LM, OpenCV)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.config import TrackingConfig
from evpose.slam.geometry import project


@dataclass
class PoseEstimate:
    ok: bool
    T_wc: np.ndarray | None = None
    """Estimated ``T_world_cam`` (4, 4)."""
    inliers: np.ndarray | None = None
    """Mask of the 2D-3D pairs within the reprojection threshold (N,)."""
    reason: str = ""
    rms_px: float = float("nan")
    """RMS reprojection error of the inliers, pixels."""
    prior_sigmas: tuple[float, float] | None = None
    """(rotation rad, translation map units) of the motion prior the pose was refined with
    (:mod:`evpose.slam.pnp_motion_prior`); None: none."""


def estimate_pose(K: np.ndarray, Xw: np.ndarray, uv: np.ndarray, T_wc_guess: np.ndarray, cfg: TrackingConfig, seed: int = 0) -> PoseEstimate:
    """Pose from 2D-3D pairs, started from ``T_wc_guess`` (constant-velocity prediction).

    The final Levenberg-Marquardt refinement starts at RANSAC's pose. Session 20 (``/tmp/s20/post9/lmguess.py``): started
    at ``T_wc_guess`` instead, on the same inliers, the landing event-only runs (72 seeds, defaults 2.40 %, 46 within
    2 %) gave 2.47 % (50 within 2 %, median 1.75 either way), paired +0.07 +- 0.25 points, 36 better and 36 worse
    (seeds 0-23 1.82 -> 2.75 %, 24-47 2.86 -> 2.23 %, 48-71 2.51 -> 2.43 %): the start moves where the solver stops
    along the flat rotation-translation valley after the turn, and reshuffles which seeds run away
    (:attr:`TrackingConfig.ba_window`); not kept. Session 23: per-point sigmas in this refinement (from each track's
    summed inverse event mass or its PnP residual history) made the landing worse; figures in :mod:`evpose.slam.features`.
    """
    n = len(Xw)
    if n < cfg.min_inliers:
        return PoseEstimate(False, reason=f"{n} tracked map points < {cfg.min_inliers}")
    obj = np.ascontiguousarray(Xw, np.float64).reshape(-1, 1, 3)
    img = np.ascontiguousarray(uv, np.float64).reshape(-1, 1, 2)
    T_cw = invert_pose(T_wc_guess)
    rvec, _ = cv2.Rodrigues(T_cw[:3, :3])
    tvec = T_cw[:3, 3].reshape(3, 1).copy()
    cv2.setRNGSeed(seed)
    try:
        ok, rvec, tvec, inl = cv2.solvePnPRansac(obj, img, K, None, rvec, tvec, useExtrinsicGuess=True, iterationsCount=100, reprojectionError=cfg.reprojection_threshold_px, confidence=0.99, flags=cv2.SOLVEPNP_ITERATIVE)
        if not ok or inl is None or len(inl) < cfg.min_inliers:
            return PoseEstimate(False, reason=f"PnP found {0 if inl is None else len(inl)} inliers < {cfg.min_inliers}")
        idx = inl.ravel()
        rvec, tvec = cv2.solvePnPRefineLM(obj[idx], img[idx], K, None, rvec, tvec)
    except cv2.error as exc:
        # OpenCV's solvers assert on degenerate samples (seen with its five-point solver, see
        # :func:`evpose.slam.initialization.initialize_two_view`): a failed estimate, never an exception out of a run.
        return PoseEstimate(False, reason=f"PnP failed: {str(exc).strip().splitlines()[-1]}")
    R, _ = cv2.Rodrigues(rvec)
    T_cw = np.eye(4)
    T_cw[:3, :3] = R
    T_cw[:3, 3] = tvec.ravel()
    proj, z = project(K, T_cw, np.asarray(Xw, np.float64))
    err = np.linalg.norm(proj - uv, axis=1)
    inliers = (z > 0) & (err < cfg.reprojection_threshold_px)
    if inliers.sum() < cfg.min_inliers:
        return PoseEstimate(False, reason=f"{int(inliers.sum())} inliers after refinement < {cfg.min_inliers}")
    if inliers.sum() < cfg.min_inlier_ratio * n:
        return PoseEstimate(False, reason=f"only {int(inliers.sum())} of {n} tracked map points agree with the pose")
    return PoseEstimate(True, invert_pose(T_cw), inliers, rms_px=float(np.sqrt(np.mean(err[inliers] ** 2))))
