"""Pose predictions for MCIs the images cannot place: the motion model, and dropping associations that contradict it.

Event-inertial C2/C3 keep a map through visual failures instead of opening a
new one. A metric map (IMU initialised) is propagated by the preintegrated IMU
(:mod:`evpose.slam.inertial_bridge`); a map not yet initialised *coasts*: the
gyro gives the rotation and the map's own recent motion, held constant in the
camera frame, the translation (in map units: the scale is still unknown).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.geometry import project


def constant_velocity_pose(m: SlamMap, t_us: int) -> np.ndarray:
    """``T_world_cam`` at ``t_us`` from the last two poses of ``m``, the motion between them scaled to the time step."""
    guess = m.traj_T[-1]
    if len(m.traj_t) >= 2:
        D = invert_pose(m.traj_T[-2]) @ m.traj_T[-1]
        dt_prev = max(m.traj_t[-1] - m.traj_t[-2], 1)
        a = (t_us - m.traj_t[-1]) / dt_prev
        # Beyond four steps the extrapolation is a guess of a guess; the last pose is safer.
        if 0 < a < 4:
            Da = np.eye(4)
            Da[:3, :3] = Rotation.from_rotvec(Rotation.from_matrix(D[:3, :3]).as_rotvec() * a).as_matrix()
            Da[:3, 3] = D[:3, 3] * a
            guess = m.traj_T[-1] @ Da
    return guess


def camera_frame_velocity(m: SlamMap, min_span_us: int, end: int = -1) -> np.ndarray | None:
    """Velocity of the camera in its own frame (map units per us), averaged over the newest poses spanning ``min_span_us``
    (up to the pose at index ``end``).

    Two consecutive MCIs are a few ms apart and a few mm of motion; their difference is mostly pose noise, so the
    coasting speed comes from a longer stretch of the trajectory. None when the map has not moved for that long.
    """
    span = trajectory_span(m, min_span_us, end)
    if span is None:
        return None
    k, dt = span
    T_end = m.traj_T[end]
    return T_end[:3, :3].T @ (T_end[:3, 3] - m.traj_T[k][:3, 3]) / dt


def trajectory_span(m: SlamMap, min_span_us: int, end: int = -1) -> tuple[int, int] | None:
    """(index of the newest pose at least ``min_span_us`` before the map's last one (or the one at index ``end``), that
    span in us); None when the map's trajectory is shorter than that."""
    end = end % len(m.traj_t) if m.traj_t else 0
    if end < 1:
        return None
    t_end = m.traj_t[end]
    k = end - 1
    while k > 0 and t_end - m.traj_t[k] < min_span_us:
        k -= 1
    dt = t_end - m.traj_t[k]
    return None if dt < min_span_us else (k, dt)


def coast_pose(m: SlamMap, t_us: int, R_wc: np.ndarray, v_cam: np.ndarray) -> np.ndarray:
    """``T_world_cam`` at ``t_us``: orientation ``R_wc`` (from the gyro), position moved by ``v_cam`` held in the camera frame.

    The camera-frame velocity is applied at the mean of the old and new orientations, so a steady turn (a camera
    circling a room) bends the path with it.
    """
    T_last = m.traj_T[-1]
    dt = t_us - m.traj_t[-1]
    R_mid = Rotation.from_matrix(np.stack([T_last[:3, :3], R_wc])).mean().as_matrix()
    T = np.eye(4)
    T[:3, :3] = R_wc
    T[:3, 3] = T_last[:3, 3] + R_mid @ v_cam * dt
    return T


def drop_contradicted(m: SlamMap, K: np.ndarray, T_wc: np.ndarray, ids: np.ndarray, uv: np.ndarray, track_to_point: dict,
                      threshold_px: float) -> int:
    """Unlink tracks whose map point reprojects farther than ``threshold_px`` from them under ``T_wc``; returns how many.

    When visual tracking fails, the associations that disagree with the predicted pose are the ones that failed
    (tracks that jumped to other features); keeping them would poison the keyframe made at the predicted pose.
    """
    rows = [(i, track_to_point[t]) for i, t in enumerate(ids.tolist()) if track_to_point.get(t) in m.points]
    if not rows:
        return 0
    Xw = np.stack([m.points[p].xyz for _, p in rows])
    obs = np.stack([uv[i] for i, _ in rows]).astype(np.float64)
    proj, z = project(K, invert_pose(T_wc), Xw)
    bad = ~(z > 0) | ~(np.linalg.norm(proj - obs, axis=1) < threshold_px)
    for (i, _), b in zip(rows, bad):
        if b:
            track_to_point.pop(int(ids[i]), None)
    return int(bad.sum())
