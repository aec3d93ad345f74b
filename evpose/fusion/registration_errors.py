"""How the registrations fed to the fusion err against ground truth: size, calibration, time correlation, coupling.

The fusion weighs each registration by its covariance; whether that is right
depends on more than the covariance's size. This module measures, on a run
with ground truth (benchmark ``fusion.registration_wander``):

* **calibration**: the NEES ``e^T C^-1 e`` of each registration error ``e``
  under its own covariance ``C`` (for a calibrated 6-DoF Gaussian the median
  is 5.35, the chi-square median);
* **time correlation**: per error axis, the integrated autocorrelation time in
  updates, ``1 + 2 sum_k rho_k`` (sum truncated at the first non-positive
  lag). The mean of ``N`` such errors has the variance of ``N / tau_int``
  independent ones, so ``tau_int`` is the factor by which treating the errors as
  white overstates the information of a run of registrations: the statistical
  reading of ``FusionConfig.registration_covariance_scale``;
* **tilt/shift coupling**: a downward camera over a near-planar scene confuses a
  shift along camera x with a rotation about camera y (and y with x). The
  empirical slope ``d e_tx / d e_ry`` is compared with the covariance's own
  ``C_tx,ry / C_ry,ry``; and the translation error is *conditioned* on the true
  rotation (``e_t - C_tr C_rr^-1 e_r``): what remains if the fusion knew the
  rotation exactly (from the gyro) and used the covariance's cross terms.

Errors are in the camera (body) frame with gtsam's ordering and convention:
rotation ``Log(R_gt^T R)``, translation ``R_gt^T (p - p_gt)``.

Measured (moderate landing 346x260, 2 s, ``full`` from ground truth, map from
build-map at the session-3 start / from a mid-session mapping revision): registration errors 23.5 /
17.7 mm RMS, covariance about 1.5-2x conservative (NEES median 3.5 / 2.4),
integrated autocorrelation time 49 / 63 updates (0.25-0.3 s), tilt/shift slope
-3.80 m/rad measured against -3.86 in the covariance (correlation -0.98);
knowing the rotation would leave 14.4 / 8.1 mm, mostly depth (13.0 / 5.9 mm).
The fusion gets 17.7 / 16.0 mm online; with the simulator's true IMU biases
dead reckoning alone gets 3.0 mm: the 2 s run cannot tell an accelerometer
bias (0.05-0.08 m/s^2 here) or a gyro bias from a registration error that
wanders this slowly, so the online estimate follows the wander.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory

AXES = ("rx", "ry", "rz", "tx", "ty", "tz")
CHI2_6_MEDIAN = 5.348
"""Median of the chi-square distribution with 6 degrees of freedom (the NEES of a calibrated 6-DoF Gaussian)."""


def pose_error_vectors(t_us: np.ndarray, poses: np.ndarray, ground_truth: Trajectory) -> np.ndarray:
    """(N, 6) errors ``(rotation rad, translation m)`` of camera poses (N, 4, 4) against the ground truth, camera frame."""
    gt = ground_truth.interpolate(np.asarray(t_us, np.int64))
    G = gt.matrices()
    P = np.asarray(poses, np.float64)
    rot = Rotation.from_matrix(np.einsum("nji,njk->nik", G[:, :3, :3], P[:, :3, :3])).as_rotvec()
    trans = np.einsum("nji,nj->ni", G[:, :3, :3], P[:, :3, 3] - G[:, :3, 3])
    return np.concatenate([rot, trans], axis=1)


def poses_with_errors(t_us: np.ndarray, errors: np.ndarray, ground_truth: Trajectory) -> np.ndarray:
    """Camera poses (N, 4, 4) that carry the given (N, 6) errors against the ground truth: the inverse of
    :func:`pose_error_vectors` (rotation ``R_gt Exp(e_r)``, position ``p_gt + R_gt e_t``)."""
    G = ground_truth.interpolate(np.asarray(t_us, np.int64)).matrices()
    e = np.asarray(errors, np.float64)
    out = np.tile(np.eye(4), (len(e), 1, 1))
    out[:, :3, :3] = np.einsum("nij,njk->nik", G[:, :3, :3], Rotation.from_rotvec(e[:, :3]).as_matrix())
    out[:, :3, 3] = G[:, :3, 3] + np.einsum("nij,nj->ni", G[:, :3, :3], e[:, 3:])
    return out


def slow_part(errors: np.ndarray, window: int) -> np.ndarray:
    """Centred moving average of (N, 6) error series over ``window`` samples (ends padded with the end values): the
    part of the errors slower than about ``window`` samples. Two-sided, so an offline (oracle) decomposition."""
    e = np.asarray(errors, np.float64)
    w = max(int(window), 1)
    padded = np.pad(e, ((w // 2, w - 1 - w // 2), (0, 0)), mode="edge")
    c = np.cumsum(np.vstack([np.zeros((1, e.shape[1])), padded]), axis=0)
    return (c[w:] - c[:-w]) / w


def ate_are(t_us: np.ndarray, poses: np.ndarray, ground_truth: Trajectory) -> tuple[float, float]:
    """RMS translation error (mm) and RMS rotation angle (deg) of camera poses against the ground truth, no alignment."""
    e = pose_error_vectors(t_us, poses, ground_truth)
    return float(np.sqrt(np.mean(np.sum(e[:, 3:] ** 2, 1))) * 1e3), float(np.degrees(np.sqrt(np.mean(np.sum(e[:, :3] ** 2, 1)))))


def integrated_autocorrelation(x: np.ndarray, max_lag: int | None = None) -> float:
    """``1 + 2 sum_{k>=1} rho_k`` of a series, summing until the first non-positive autocorrelation, in samples."""
    x = np.asarray(x, np.float64) - np.mean(x)
    n = x.shape[0]
    var = float(x @ x)
    if n < 3 or var <= 0.0:
        return 1.0
    tau = 1.0
    for k in range(1, min(n - 1, max_lag or n // 2)):
        rho = float(x[:-k] @ x[k:]) / var
        if rho <= 0.0:
            break
        tau += 2.0 * rho
    return tau


def analyse_registration_errors(errors: np.ndarray, covariances: np.ndarray) -> dict:
    """Figures of (N, 6) registration errors and their (N, 6, 6) covariances (see the module docstring)."""
    e = np.asarray(errors, np.float64)
    C = np.asarray(covariances, np.float64)
    if e.ndim != 2 or e.shape[1] != 6 or C.shape != (e.shape[0], 6, 6) or e.shape[0] < 3:
        raise ValueError(f"need (N, 6) errors and (N, 6, 6) covariances with N >= 3, got {e.shape} and {C.shape}")
    out: dict = {"registrations": int(e.shape[0])}
    for i, name in enumerate(AXES):
        scale = 1e3 if i >= 3 else np.degrees(1.0)
        out[f"rms_{name}_{'mm' if i >= 3 else 'deg'}"] = float(np.sqrt(np.mean(e[:, i] ** 2)) * scale)
        out[f"sigma_median_{name}_{'mm' if i >= 3 else 'deg'}"] = float(np.median(np.sqrt(C[:, i, i])) * scale)
        out[f"autocorrelation_time_{name}_updates"] = integrated_autocorrelation(e[:, i])
    out["autocorrelation_time_median_updates"] = float(np.median([out[f"autocorrelation_time_{a}_updates"] for a in AXES]))
    nees = np.einsum("ni,ni->n", e, np.linalg.solve(C, e[:, :, None])[:, :, 0])
    out["nees_median"] = float(np.median(nees))
    out["nees_median_calibrated"] = CHI2_6_MEDIAN
    # Tilt/shift: translation x against rotation about y, translation y against rotation about x (camera frame).
    for t_ax, r_ax in ((3, 1), (4, 0)):
        tag = f"{AXES[t_ax]}_per_{AXES[r_ax]}"
        out[f"slope_{tag}_empirical_m_per_rad"] = float(np.polyfit(e[:, r_ax], e[:, t_ax], 1)[0])
        out[f"slope_{tag}_covariance_m_per_rad"] = float(np.median(C[:, t_ax, r_ax] / C[:, r_ax, r_ax]))
        out[f"correlation_{tag}_covariance"] = float(np.median(C[:, t_ax, r_ax] / np.sqrt(C[:, t_ax, t_ax] * C[:, r_ax, r_ax])))
    gain = np.einsum("nij,njk->nik", C[:, 3:, :3], np.linalg.inv(C[:, :3, :3]))
    cond = e[:, 3:] - np.einsum("nij,nj->ni", gain, e[:, :3])
    for i, name in enumerate(AXES[3:]):
        out[f"rms_{name}_given_true_rotation_mm"] = float(np.sqrt(np.mean(cond[:, i] ** 2)) * 1e3)
    out["rms_translation_mm"] = float(np.sqrt(np.mean(np.sum(e[:, 3:] ** 2, axis=1))) * 1e3)
    out["rms_translation_given_true_rotation_mm"] = float(np.sqrt(np.mean(np.sum(cond**2, axis=1))) * 1e3)
    return out
