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

    Why event-only PnP keyframes step short (session 41, ``/tmp/s41/pnp41``: ``h.py`` runs ``evpose slam`` + ``evpose
    eval --atlas --correct-scale`` in-process, byte-identical to the CLI on indoor seed 0; h = log(step / true step) of
    each PnP-placed keyframe from the previous one, in its map's Sim(3) scale). Against the map's previous 3 keyframe
    steps after their local BA (session 40's measure) h is -0.27 +- 0.08 on indoor seeds 0-8 (85 keyframes) and -0.12
    +- 0.03 on landing 0-1. Not this function: started from zero motion or twice the predicted step instead of the
    prediction, all 114 poses come out the same (``guess.py``), and the motion prior (``pnp_motion_prior_ratio``) is off.
    Not KLT lag: each MCI-to-MCI step against the true flow of a ray-cast point, median ratio 0.94-1.01 (``klt.py``);
    between keyframes the inliers move 0.26 px (median) MORE than their birth points. What it is: tracks drift ahead
    over their lives (``birth.py``): 32 % (landing 41 %) of the PnP inliers sit 3-20 px off the true projection of the
    point they were born on, two thirds of them ahead along the image motion (median 4.2 px), and the map points of those
    ahead are triangulated nearer (``depth.py``, log depth against their keyframe's median: ahead -0.08, within 3 px
    +0.03, behind +0.17; landing -0.04 / 0.00 / +0.04): their extra parallax makes near points, and PnP on near points
    steps short. The keyframe's own local BA then lengthens the step (+0.18 +- 0.04, landing +0.15 +- 0.04) to about its
    final length in the map (final against after that BA -0.03 +- 0.04). Diagnosis with every track moved each MCI to
    its birth point's true projection (closed loop, ``ORACLE_TRK=1``): h -0.05 +- 0.03 (landing -0.03 +- 0.01), BA gain
    +0.05 (+0.02), landing ATE 1.09 / 1.97 -> 0.53 / 0.53 % at the same tracked time (indoor mixed: such tracks outlive
    occlusions, tracked 66-91 %). Correcting only the tracks within 3 px of the truth, or dropping those further off,
    leaves it (-0.24 / -0.19, indoor 0-3). The true camera rotation as a gyro prior (``ORACLE_ROT=1``) makes it worse
    (-0.41, BA gain +0.60, indoor 0-2), though the event-only maps turn 1.28 times the true rotation over 0.1 s (median of 45
    indoor maps, 0.73-4.69; landing 1.04). Triangulating a keyframe's new points from its pose after its BA instead of
    the PnP pose (harness ``TRI_AFTER=1``, ``pair.py``): indoor 0-9 1.959 -> 1.714 % (paired -0.245 +- 0.258, 6 better,
    4 worse; seed 5 4.32 -> 1.98), landing 0 / 1 1.09 -> 1.27 / 1.97 -> 8.92 %, h -0.33: not kept. The lever is the
    drift of long tracks, not this solver.
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
