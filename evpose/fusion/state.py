"""The fused estimate every backend returns, and the camera <-> IMU-body conversions they share.

Backends estimate the IMU body pose ``T_world_imu`` (what the IMU factor
constrains); the public API speaks camera poses: ``T_world_imu = T_world_cam @ T_cam_imu``.
Covariances are 6x6 in gtsam's Pose3 tangent order (rotation, translation),
expressed in the body frame of the pose they belong to (right perturbation
``T * Exp(xi)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.trajectory import invert_pose, skew


@dataclass
class FusedState:
    """One fused estimate of the camera state."""

    t_us: int
    """Time of the estimate, microseconds (camera clock)."""
    T_world_cam: np.ndarray
    """Camera pose (4, 4), maps camera-frame points into the world."""
    velocity_world: np.ndarray
    """Velocity of the camera centre in the world, (3,), m/s."""
    acc_bias: np.ndarray
    """Accelerometer bias estimate (3,), m/s^2, IMU frame."""
    gyro_bias: np.ndarray
    """Gyroscope bias estimate (3,), rad/s, IMU frame."""
    covariance: np.ndarray | None = None
    """(6, 6) covariance of ``T_world_cam`` (rotation, translation; camera body frame), or None."""
    degraded: bool = False
    """True when no registration supported this estimate (IMU propagation only)."""
    omega_cam: np.ndarray | None = None
    """Bias-corrected angular rate of the camera in the camera frame (3,), rad/s, if known."""
    readout_T_world_cam: np.ndarray | None = None
    """The pose to write for this state instead of ``T_world_cam`` (4, 4), or None: ``T_world_cam`` moved by the
    smoother's revisions of older states (``FusionConfig.revision_readout_states``); never fed back."""

    def copy(self) -> "FusedState":
        cp = lambda a: None if a is None else np.array(a, copy=True)  # noqa: E731
        return FusedState(int(self.t_us), cp(self.T_world_cam), cp(self.velocity_world), cp(self.acc_bias), cp(self.gyro_bias),
                          cp(self.covariance), bool(self.degraded), cp(self.omega_cam), cp(self.readout_T_world_cam))


def adjoint(T: np.ndarray) -> np.ndarray:
    """6x6 adjoint of a rigid transform in (rotation, translation) tangent order (gtsam's Pose3.AdjointMap)."""
    R = T[:3, :3]
    out = np.zeros((6, 6))
    out[:3, :3] = R
    out[3:, 3:] = R
    out[3:, :3] = skew(T[:3, 3]) @ R
    return out


class Extrinsic:
    """Converts poses, velocities and covariances between the camera and the IMU body."""

    def __init__(self, T_cam_imu: np.ndarray):
        self.T_cam_imu = np.asarray(T_cam_imu, dtype=np.float64).reshape(4, 4)
        self.T_imu_cam = invert_pose(self.T_cam_imu)
        # T_world_imu = T_world_cam T_cam_imu: a camera-body perturbation xi_c maps to xi_i = Ad(T_imu_cam) xi_c.
        self._ad_cam_to_imu = adjoint(self.T_imu_cam)
        self._ad_imu_to_cam = adjoint(self.T_cam_imu)
        self.lever_imu = self.T_imu_cam[:3, 3].copy()
        """Camera centre in the IMU frame, metres."""
        self.R_cam_imu = self.T_cam_imu[:3, :3].copy()

    def imu_pose(self, T_world_cam: np.ndarray) -> np.ndarray:
        return np.asarray(T_world_cam, dtype=np.float64) @ self.T_cam_imu

    def cam_pose(self, T_world_imu: np.ndarray) -> np.ndarray:
        return np.asarray(T_world_imu, dtype=np.float64) @ self.T_imu_cam

    def imu_covariance(self, cov_cam: np.ndarray) -> np.ndarray:
        return self._ad_cam_to_imu @ cov_cam @ self._ad_cam_to_imu.T

    def cam_covariance(self, cov_imu: np.ndarray) -> np.ndarray:
        return self._ad_imu_to_cam @ cov_imu @ self._ad_imu_to_cam.T

    def cam_velocity(self, R_world_imu: np.ndarray, v_imu_world: np.ndarray, omega_imu: np.ndarray) -> np.ndarray:
        """Velocity of the camera centre: v_c = v_i + R_wi (omega x lever)."""
        return v_imu_world + R_world_imu @ (skew(omega_imu) @ self.lever_imu)

    def imu_velocity(self, R_world_imu: np.ndarray, v_cam_world: np.ndarray, omega_imu: np.ndarray) -> np.ndarray:
        return v_cam_world - R_world_imu @ (skew(omega_imu) @ self.lever_imu)

    def cam_omega(self, omega_imu: np.ndarray) -> np.ndarray:
        """Angular rate in the camera frame."""
        return self.R_cam_imu @ omega_imu
