"""IMU measurements from a rig trajectory: specific force and body rates plus noise and biases.

Ideal values: ``f = R_wb^T (a_w - g_w)`` with ``g_w = (0, 0, -9.81)`` and the body
rate ``omega_b``. Noise follows the continuous-time model used by Kalibr and
gtsam: white noise of density ``sigma`` (per sqrt(Hz)) becomes a discrete
standard deviation ``sigma * sqrt(rate)``; biases are random walks of density
``sigma_b`` (per sqrt(s)) whose increments over one sample period ``dt`` have
standard deviation ``sigma_b * sqrt(dt)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.imu import ImuSamples
from evpose.sim.trajectories import RigTrajectory

GRAVITY_W = np.array([0.0, 0.0, -9.81])


@dataclass(frozen=True)
class ImuConfig:
    """Rate and noise model of the simulated IMU (defaults: a consumer MEMS part like the BMI088)."""

    rate_hz: int = field(default=500, metadata={"min": 200, "max": 1000, "unit": "Hz"})
    """Sample rate, Hz; must divide 1e6 so samples fall on whole microseconds."""
    acc_noise_density: float = 2.0e-3
    """Accelerometer white-noise density, m/s^2/sqrt(Hz)."""
    gyro_noise_density: float = 1.7e-4
    """Gyroscope white-noise density, rad/s/sqrt(Hz)."""
    acc_bias_random_walk: float = 3.0e-4
    """Accelerometer bias random-walk density, m/s^3/sqrt(Hz)."""
    gyro_bias_random_walk: float = 2.0e-5
    """Gyroscope bias random-walk density, rad/s^2/sqrt(Hz)."""
    acc_bias_initial: float = 0.05
    """Standard deviation of the initial accelerometer bias per axis, m/s^2."""
    gyro_bias_initial: float = 0.002
    """Standard deviation of the initial gyroscope bias per axis, rad/s."""
    noise_free: bool = False
    """Ideal measurements (no noise, no bias): for tests."""


@dataclass
class ImuTruth:
    """What the IMU measured and the hidden biases, for evaluation."""

    samples: ImuSamples
    acc_bias: np.ndarray
    """(N, 3) true accelerometer bias at each sample, m/s^2."""
    gyro_bias: np.ndarray
    """(N, 3) true gyroscope bias at each sample, rad/s."""


def ideal_imu(traj: RigTrajectory, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free specific force (N, 3) and body rates (N, 3) at the given times (seconds)."""
    R_wb = traj.body_rotation(t_s)
    f = R_wb.inv().apply(traj.body_acceleration(t_s) - GRAVITY_W)
    return f, traj.body_rates(t_s)


def simulate_imu(traj: RigTrajectory, cfg: ImuConfig, t0_us: int, t1_us: int, rng: np.random.Generator) -> ImuTruth:
    """IMU samples on ``[t0_us, t1_us]`` at ``cfg.rate_hz``."""
    if 1_000_000 % int(cfg.rate_hz) != 0:
        from evpose.errors import ConfigError

        raise ConfigError(f"IMU rate {cfg.rate_hz} Hz does not divide 1 s into whole microseconds")
    period = 1_000_000 // int(cfg.rate_hz)
    t_us = np.arange(t0_us, t1_us + 1, period, dtype=np.int64)
    f, w = ideal_imu(traj, t_us * 1e-6)
    n = t_us.size
    if cfg.noise_free:
        return ImuTruth(ImuSamples.from_arrays(t_us, f, w), np.zeros((n, 3)), np.zeros((n, 3)))
    dt = period * 1e-6
    ba = cfg.acc_bias_initial * rng.standard_normal(3) + np.cumsum(cfg.acc_bias_random_walk * np.sqrt(dt) * rng.standard_normal((n, 3)), axis=0)
    bg = cfg.gyro_bias_initial * rng.standard_normal(3) + np.cumsum(cfg.gyro_bias_random_walk * np.sqrt(dt) * rng.standard_normal((n, 3)), axis=0)
    acc = f + ba + cfg.acc_noise_density / np.sqrt(dt) * rng.standard_normal((n, 3))
    gyro = w + bg + cfg.gyro_noise_density / np.sqrt(dt) * rng.standard_normal((n, 3))
    return ImuTruth(ImuSamples.from_arrays(t_us, acc, gyro), ba, bg)
