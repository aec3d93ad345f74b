"""Helpers shared by the fusion tests (a plain module: importing from conftest is ambiguous across test folders)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.fusion.synthetic import AnalyticMotion, AnalyticMotionConfig


WHITE = {"registration_covariance_scale": 1.0}
"""FusionConfig keywords for the synthetic registrations here: white noise, so their covariance is taken as is
(the default scale is for the correlated errors of real registrations)."""


def make_motion(**kw) -> AnalyticMotion:
    return AnalyticMotion(AnalyticMotionConfig(**kw))


def noisy_registrations(motion, T_cam_imu, times_us, sigma_trans, sigma_rot, seed=0):
    """Ground-truth camera poses perturbed by Gaussian noise of the given sigmas (body frame), with their covariance."""
    rng = np.random.default_rng(seed)
    gt = motion.camera_trajectory(times_us, T_cam_imu)
    out = []
    for k in range(len(gt)):
        T = gt.matrix(k)
        T[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(rng.normal(0, sigma_rot, 3)).as_matrix()
        T[:3, 3] += T[:3, :3] @ rng.normal(0, sigma_trans, 3)
        out.append(T)
    cov = np.diag([sigma_rot**2] * 3 + [sigma_trans**2] * 3)
    return gt, out, cov


def pose_errors(T_est, T_gt):
    """(translation error m, rotation error rad)."""
    dt = np.linalg.norm(T_est[:3, 3] - T_gt[:3, 3])
    dr = np.linalg.norm(Rotation.from_matrix(T_est[:3, :3].T @ T_gt[:3, :3]).as_rotvec())
    return dt, dr


ALIGNED_W, ALIGNED_H = 64, 48
"""Sensor of the small aligned-surface scenes (T_align tests), pixels."""
ALIGNED_K = np.array([[50.0, 0, 32.0], [0, 50.0, 24.0], [0, 0, 1]])
ALIGNED_DEPTH = 2.0
"""Depth of every map point of those scenes (camera at the origin looking along +z), metres."""


def points_at(uv) -> np.ndarray:
    """World points at ``ALIGNED_DEPTH`` that project to pixel positions ``uv`` through ``ALIGNED_K``."""
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    K, d = ALIGNED_K, ALIGNED_DEPTH
    return np.c_[(uv[:, 0] - K[0, 2]) / K[0, 0] * d, (uv[:, 1] - K[1, 2]) / K[1, 1] * d, np.full(len(uv), d)]



def update_with_replay(fusion, times, regs, cov, snapshot_at=None):
    """Feed ``regs`` (one per time, covariance ``cov``) to ``fusion``; with ``snapshot_at`` also snapshot before that
    update, restore at the end and feed the rest again. Returns (states, states of the replay or None)."""
    states, again, snap = [], None, None
    for k, t in enumerate(times):
        if k == snapshot_at:
            snap = fusion.snapshot()
        states.append(fusion.update(int(t), regs[k], cov))
    if snap is not None:
        fusion.restore(snap)
        again = [fusion.update(int(times[k]), regs[k], cov) for k in range(snapshot_at, len(times))]
    return states, again
