"""Event-only coasting: the pose of an MCI the map cannot place, predicted from the map's own recent motion.

Event-inertial maps coast on the gyro (:mod:`evpose.slam.coasting`); without an
IMU both the rotation and the translation come from the newest poses of the map,
held constant in the camera frame over a stretch long enough (several MCIs) that
pose noise averages out. The simulated indoor room turns at 20-110 deg/s and
changes that rate by at most ~130 deg/s^2, so over 0.1 s a constant rate is off
by well under a degree, against the many degrees a re-initialised map gets wrong.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import SlamMap
from evpose.slam.coasting import camera_frame_velocity, coast_pose, trajectory_span


def camera_frame_rate(m: SlamMap, min_span_us: int) -> np.ndarray | None:
    """Angular velocity of the camera in its own frame (rad per us), over the newest poses spanning ``min_span_us``.

    None when the map's trajectory is shorter than that.
    """
    span = trajectory_span(m, min_span_us)
    if span is None:
        return None
    k, dt = span
    R_rel = m.traj_T[k][:3, :3].T @ m.traj_T[-1][:3, :3]
    return Rotation.from_matrix(R_rel).as_rotvec() / dt


def event_only_coast_pose(m: SlamMap, t_us: int, min_span_us: int) -> np.ndarray | None:
    """``T_world_cam`` at ``t_us`` with the map's recent camera-frame rotation rate and velocity held; None without them."""
    w = camera_frame_rate(m, min_span_us)
    v = camera_frame_velocity(m, min_span_us)
    if w is None or v is None:
        return None
    dt = t_us - m.traj_t[-1]
    R_wc = m.traj_T[-1][:3, :3] @ Rotation.from_rotvec(w * dt).as_matrix()
    return coast_pose(m, t_us, R_wc, v)


def drop_unconfirmed_poses(m: SlamMap, t_last_visual_us: int) -> int:
    """Remove the trajectory poses after ``t_last_visual_us`` (coasted, and no MCI placed the map again); returns how many.

    A coast that ends in a loss was dead reckoning the images never confirmed: extrapolated over up to ``coast_s`` it
    is off by far more than the map's tracked poses, and the map's trajectory is better without it.
    """
    n = 0
    while m.traj_t and m.traj_t[-1] > t_last_visual_us:
        for lst in (m.traj_t, m.traj_T, m.traj_ref, m.traj_rel):
            lst.pop()
        n += 1
    return n
