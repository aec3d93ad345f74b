"""Analytic IMU motion for tests and benchmarks of the fusion backends.

A smooth sinusoidal flight whose IMU readings are exact: position is a sum of
sines (closed-form acceleration), orientation is a ZYX Euler sinusoid whose
body rate comes from a central difference of rotations at h = 1e-5 s (error
~1e-10 rad/s). Specific force ``f = R_wb^T (a_w - g_w)`` with ``g_w = (0, 0, -g)``.
Biases are constant plus an optional random walk; white noise is discrete
with ``sigma = density * sqrt(rate)``. Everything is seeded.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory, pose_matrix


@dataclass
class AnalyticMotionConfig:
    """Parameters of the analytic flight (z-up world, IMU body frame)."""

    duration_s: float = 4.0
    """Length of the flight, s."""
    imu_rate_hz: float = 1000.0
    """IMU sample rate, Hz."""
    amplitude_m: tuple[float, float, float] = (0.6, 0.4, 0.25)
    """Position sine amplitude per world axis, m."""
    frequency_hz: tuple[float, float, float] = (0.31, 0.43, 0.23)
    """Position sine frequency per axis, Hz."""
    angle_amplitude_rad: tuple[float, float, float] = (0.25, 0.2, 0.6)
    """Roll, pitch, yaw sine amplitudes, rad."""
    angle_frequency_hz: tuple[float, float, float] = (0.37, 0.29, 0.17)
    """Roll, pitch, yaw sine frequencies, Hz."""
    gravity: float = 9.81
    """Gravity magnitude, m/s^2."""
    acc_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Constant accelerometer bias, m/s^2."""
    gyro_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Constant gyroscope bias, rad/s."""
    accel_noise_density: float = 0.0
    """Accelerometer white noise, m/s^2/sqrt(Hz)."""
    gyro_noise_density: float = 0.0
    """Gyroscope white noise, rad/s/sqrt(Hz)."""
    t0_us: int = 1_000_000
    """Time of the first sample, us."""
    seed: int = 0
    """Seed of the noise generator."""
    centre: tuple[float, float, float] = field(default=(0.0, 0.0, 1.5))
    """Mean position, m."""


class AnalyticMotion:
    """Closed-form IMU-body trajectory with its exact IMU readings."""

    def __init__(self, config: AnalyticMotionConfig | None = None):
        self.config = config or AnalyticMotionConfig()
        c = self.config
        self._A = np.array(c.amplitude_m, float)
        self._w = 2 * np.pi * np.array(c.frequency_hz, float)
        self._B = np.array(c.angle_amplitude_rad, float)
        self._u = 2 * np.pi * np.array(c.angle_frequency_hz, float)
        self._phase = np.array([0.3, 1.1, 2.0])

    def _s(self, t_us) -> np.ndarray:
        return (np.asarray(t_us, dtype=np.float64) - self.config.t0_us) * 1e-6

    def position(self, t_us) -> np.ndarray:
        s = self._s(t_us)[..., None]
        return np.asarray(self.config.centre) + self._A * np.sin(self._w * s + self._phase)

    def velocity(self, t_us) -> np.ndarray:
        s = self._s(t_us)[..., None]
        return self._A * self._w * np.cos(self._w * s + self._phase)

    def acceleration(self, t_us) -> np.ndarray:
        s = self._s(t_us)[..., None]
        return -self._A * self._w**2 * np.sin(self._w * s + self._phase)

    def _rotation_s(self, s) -> Rotation:
        s = np.atleast_1d(np.asarray(s, np.float64))[:, None]
        rpy = self._B * np.sin(self._u * s + self._phase[::-1])
        return Rotation.from_euler("ZYX", rpy[:, ::-1])

    def rotation(self, t_us) -> Rotation:
        return self._rotation_s(self._s(t_us))

    def body_rate(self, t_us) -> np.ndarray:
        s = np.atleast_1d(self._s(t_us))
        h = 1e-5
        return (self._rotation_s(s - h).inv() * self._rotation_s(s + h)).as_rotvec() / (2 * h)

    def pose_imu(self, t_us) -> np.ndarray:
        """``T_world_imu`` (N, 4, 4)."""
        return pose_matrix(self.rotation(t_us), self.position(np.atleast_1d(t_us)))

    def imu(self, t_end_us: int | None = None) -> ImuSamples:
        """IMU samples over the whole flight (biases and noise from the config)."""
        c = self.config
        n = int(round(c.duration_s * c.imu_rate_hz)) + 1
        t = c.t0_us + np.round(np.arange(n) * 1e6 / c.imu_rate_hz).astype(np.int64)
        if t_end_us is not None:
            t = t[t <= t_end_us]
        R = self.rotation(t)
        g = np.array([0.0, 0.0, -c.gravity])
        f = R.inv().apply(self.acceleration(t) - g)
        w = self.body_rate(t)
        rng = np.random.default_rng(c.seed)
        sq = np.sqrt(c.imu_rate_hz)
        f = f + np.asarray(c.acc_bias) + rng.standard_normal(f.shape) * c.accel_noise_density * sq
        w = w + np.asarray(c.gyro_bias) + rng.standard_normal(w.shape) * c.gyro_noise_density * sq
        return ImuSamples.from_arrays(t, f, w)

    def camera_trajectory(self, t_us, T_cam_imu: np.ndarray) -> Trajectory:
        """Ground-truth camera poses ``T_world_cam = T_world_imu @ inv(T_cam_imu)``."""
        t_us = np.atleast_1d(np.asarray(t_us, np.int64))
        T = self.pose_imu(t_us) @ np.linalg.inv(T_cam_imu)
        return Trajectory.from_matrices(t_us, T)

    def camera_velocity(self, t_us, T_cam_imu: np.ndarray) -> np.ndarray:
        """World velocity of the camera centre (N, 3), m/s."""
        t_us = np.atleast_1d(np.asarray(t_us, np.int64))
        lever = np.linalg.inv(T_cam_imu)[:3, 3]
        R = self.rotation(t_us)
        return self.velocity(t_us) + R.apply(np.cross(self.body_rate(t_us), lever))


def default_T_cam_imu() -> np.ndarray:
    """A downward-looking camera 5 cm from the IMU: camera z = body -z, camera x = body y."""
    R_imu_cam = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) @ np.diag([1.0, -1.0, -1.0])
    T_imu_cam = np.eye(4)
    T_imu_cam[:3, :3] = R_imu_cam
    T_imu_cam[:3, 3] = [0.05, 0.01, -0.02]
    return np.linalg.inv(T_imu_cam)


def flight_with_registrations(seconds: float, rate_hz: float, seed: int):
    """A MEMS-IMU analytic flight and noisy registrations at ``rate_hz`` (2 % gross outliers, a few 50-150 ms losses)."""
    from evpose.core.camera import CameraCalibration

    cal = CameraCalibration(346, 260, 300.0, 300.0, 172.5, 129.5, T_cam_imu=default_T_cam_imu())
    motion = AnalyticMotion(AnalyticMotionConfig(duration_s=seconds + 0.2, imu_rate_hz=1000.0, acc_bias=(0.08, -0.05, 0.1),
                                                 gyro_bias=(0.01, -0.02, 0.015), accel_noise_density=2e-3,
                                                 gyro_noise_density=1.7e-4, seed=seed))
    t0 = motion.config.t0_us
    times = t0 + np.round(np.arange(1, int(seconds * rate_hz) + 1) * 1e6 / rate_hz).astype(np.int64)
    gt = motion.camera_trajectory(times, cal.T_cam_imu)
    rng = np.random.default_rng(seed + 1)
    regs: list = []
    for k in range(len(gt)):
        T = gt.matrix(k)
        T[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(rng.normal(0, np.radians(0.3), 3)).as_matrix()
        T[:3, 3] += T[:3, :3] @ rng.normal(0, 0.005, 3) + (rng.normal(0, 0.1, 3) if rng.random() < 0.02 else 0.0)
        regs.append(T)
    for start in rng.integers(100, len(regs) - 50, max(1, len(regs) // 400)):
        for k in range(int(start), min(len(regs), int(start) + int(rng.integers(10, 30)))):
            regs[k] = None  # tracking lost: the fusion bridges with the IMU
    cov = np.diag([np.radians(0.3) ** 2] * 3 + [0.005**2] * 3)
    first = (int(t0), motion.camera_trajectory([t0], cal.T_cam_imu).matrix(0), motion.camera_velocity([t0], cal.T_cam_imu)[0])
    return cal, motion.imu(), first, times, regs, cov
