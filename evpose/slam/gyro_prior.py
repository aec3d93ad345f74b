"""Gyroscope rotation priors for event-inertial tracking.

A camera looking at a nearly planar scene (a landing pad seen from above, a
wall) cannot separate a small tilt from a small sideways shift: both move the
image almost alike. Per-MCI PnP then trades rotation error for translation error
(about 1 deg per MCI on the simulated landing). The gyroscope measures the
rotation between two MCIs to a few thousandths of a degree, so event-inertial
tracking refines each pose with the reprojection error *and* a prior on its
rotation relative to the previous pose.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.imu import ImuSamples
from evpose.slam.reprojection_normal_equations import refine_with_prior


def gyro_delta_rotation(imu: ImuSamples, t0_us: int, t1_us: int, bias: np.ndarray | None = None) -> np.ndarray | None:
    """Body rotation ``R_b0_b1`` (3, 3) integrated from the gyro over ``[t0, t1)`` (sample-and-hold), None if uncovered."""
    if imu is None or len(imu) < 2 or t1_us <= t0_us or t0_us < imu.t[0] or t1_us > imu.t[-1]:
        return None
    b = np.zeros(3) if bias is None else np.asarray(bias, np.float64)
    i0 = max(int(np.searchsorted(imu.t, t0_us, side="right")) - 1, 0)
    i1 = int(np.searchsorted(imu.t, t1_us, side="left"))
    ts = imu.t[i0 : max(i1, i0 + 1)].astype(np.int64)
    a = np.maximum(ts, t0_us)
    e = np.minimum(np.r_[imu.t[i0 + 1 : max(i1, i0 + 1)], t1_us].astype(np.int64), t1_us)
    dt = np.maximum(e - a, 0) / 1e6
    rv = (imu.gyro[i0 : i0 + len(ts)] - b) * dt[:, None]
    R = np.eye(3)
    # Right-multiplied body increments; a few dozen samples per MCI, so a plain loop is cheap.
    for M in Rotation.from_rotvec(rv).as_matrix():
        R = R @ M
    return R


def camera_delta_rotation(R_b0_b1: np.ndarray, T_cam_imu: np.ndarray) -> np.ndarray:
    """The camera's rotation ``R_c0_c1`` for a body rotation ``R_b0_b1`` (``T_cam_imu`` maps IMU-frame points to the camera)."""
    R_cb = np.asarray(T_cam_imu, np.float64)[:3, :3]
    return R_cb @ R_b0_b1 @ R_cb.T


def keyframe_rotation_priors(kfs: list, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int, bias: np.ndarray | None = None) -> dict:
    """``{(id_a, id_b): R_ca_cb}`` gyro rotations between consecutive keyframes (pairs the IMU does not cover are left out)."""
    out = {}
    for a, b in zip(kfs[:-1], kfs[1:]):
        dR = gyro_delta_rotation(imu, a.t_us + time_offset_us, b.t_us + time_offset_us, bias)
        if dR is not None:
            out[(a.id, b.id)] = camera_delta_rotation(dR, T_cam_imu)
    return out


def sparse_pair_sigmas(m, priors: dict, min_points: int, sigma_rad: float) -> dict:
    """``{(id_a, id_b): sigma_rad}`` for the keyframe pairs of ``priors`` where either keyframe observes fewer than
    ``min_points`` map points of ``m``."""
    seen = dict.fromkeys({k for pair in priors for k in pair}, 0)
    for p in m.points.values():
        for k in p.obs:
            if k in seen:
                seen[k] += 1
    return {pair: sigma_rad for pair in priors if min(seen[pair[0]], seen[pair[1]]) < min_points}


def reanchor_rotations(m, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int, bias: np.ndarray, refs: set | None = None) -> None:
    """Take the rotation of each MCI pose relative to its reference keyframe from the bias-corrected gyro, in place.

    Used once the IMU initialisation knows the gyro bias: before it, those rotations came from the images
    with only a loose gyro prior; the refined trajectory (``SlamMap.trajectory``) composes them with the
    optimised keyframes. ``refs`` limits the update to MCIs referring to those keyframe ids.
    """
    kf_t = {kf.id: kf.t_us for kf in m.keyframes}
    for i, (t, ref) in enumerate(zip(m.traj_t, m.traj_ref)):
        if ref not in kf_t or t == kf_t[ref] or (refs is not None and ref not in refs):
            continue
        a, b = sorted((kf_t[ref], t))
        dR = gyro_delta_rotation(imu, a + time_offset_us, b + time_offset_us, bias)
        if dR is None:
            continue
        R = camera_delta_rotation(dR, T_cam_imu)
        m.traj_rel[i][:3, :3] = R if t > kf_t[ref] else R.T


def refine_pose_with_rotation_prior(K: np.ndarray, Xw: np.ndarray, uv: np.ndarray, T_cw: np.ndarray, R_cw_prior: np.ndarray,
                                    sigma_rot_rad: float, sigma_px: float = 1.0, huber_px: float = 2.0, iterations: int = 8) -> np.ndarray:
    """Gauss-Newton on ``T_cam_world`` minimising Huber reprojection errors plus ``|Log(R_cw R_prior^T)| / sigma_rot``.

    Returns the refined ``T_cam_world`` (4, 4). Perturbations act on the left
    (``T <- Exp(delta) T``, delta = rotation, translation).
    """
    w_prior = 1.0 / max(sigma_rot_rad, 1e-9)

    def add_prior(T, H, g):
        # Rotation prior: residual Log(R R_prior^T), Jacobian ~ identity for left perturbations.
        rp = cv2.Rodrigues(T[:3, :3] @ R_cw_prior.T)[0].ravel() * w_prior  # Log map; cv2 is ~20x faster than scipy here
        H[:3, :3] += np.eye(3) * w_prior**2
        g[:3] += rp * w_prior

    return refine_with_prior(K, np.asarray(Xw, np.float64), np.asarray(uv, np.float64), T_cw, add_prior, huber_px,
                             sigma_px, iterations)

def rotation_angle_deg(R_a: np.ndarray, R_b: np.ndarray) -> float:
    """Angle of the rotation between two orientations (3, 3), degrees."""
    return float(np.degrees(Rotation.from_matrix(R_a.T @ R_b).magnitude()))
