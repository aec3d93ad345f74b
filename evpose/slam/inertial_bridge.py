"""IMU propagation of the camera pose from the last keyframe's inertial state (E-I-C2/C3 bridging of visual failures).

Uses gtsam's preintegration and ``NavState`` prediction with the map's current
bias estimate; the keyframe pose and velocity come from the inertial local BA,
so the prediction lives in the map's metric, gravity-aligned frame.
"""

from __future__ import annotations

import numpy as np

from evpose.core.imu import ImuSamples
from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe
from evpose.slam.inertial_ba import InertialState, preintegrated_measurements


def predict_camera_pose(kf: Keyframe, state: InertialState, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int, t_us: int,
                        acc_sigma: float, gyro_sigma: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(T_world_cam, world velocity of the IMU)`` at ``t_us`` propagated from keyframe ``kf``; None without a velocity or IMU coverage."""
    import gtsam

    v = state.velocities.get(kf.id)
    t0, t1 = kf.t_us + time_offset_us, int(t_us) + time_offset_us
    if v is None or t1 <= t0 or t0 < imu.t[0] or t1 > imu.t[-1]:
        return None
    T_cb = np.asarray(T_cam_imu, np.float64)
    bias = gtsam.imuBias.ConstantBias(state.bias_acc, state.bias_gyro)
    pim = preintegrated_measurements(imu, t0, t1, bias, acc_sigma, gyro_sigma)
    nav = pim.predict(gtsam.NavState(gtsam.Pose3(kf.T_wc @ T_cb), np.asarray(v, np.float64)), bias)
    T_wb = nav.pose().matrix()
    return T_wb @ invert_pose(T_cb), np.asarray(nav.velocity(), np.float64)


def fill_velocities(keyframes: list[Keyframe], state: InertialState, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int,
                    acc_sigma: float, gyro_sigma: float) -> int:
    """Give each keyframe without a velocity the one the IMU propagates from its predecessor's, in place; returns how many.

    Indoors keyframes come a few ms apart and their positions jump by centimetres where tracking re-localises: a
    finite-difference velocity between two of them was metres per second off, and the inertial BA started from it.
    """
    n = 0
    for a, b in zip(keyframes[:-1], keyframes[1:]):
        if b.id in state.velocities or a.id not in state.velocities:
            continue
        pred = predict_camera_pose(a, state, imu, T_cam_imu, time_offset_us, b.t_us, acc_sigma, gyro_sigma)
        if pred is not None:
            state.velocities[b.id] = pred[1]
            n += 1
    return n
