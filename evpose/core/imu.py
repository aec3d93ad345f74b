"""IMU sample arrays in the body frame B."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.timestamps import check_series, window_slice
from evpose.errors import InputError


MAX_ACCELERATION = 2000.0
"""Largest specific force an IMU sample may report, m/s^2 (about 200 g)."""
MAX_ANGULAR_RATE = 200.0
"""Largest angular rate an IMU sample may report, rad/s."""


@dataclass(frozen=True)
class ImuSamples:
    """Time-sorted accelerometer and gyroscope samples.

    The accelerometer measures specific force ``f = R_wb^T (a_w - g_w)`` with
    ``g_w = (0, 0, -9.81)`` m/s^2 in z-up worlds, so a resting IMU reads +9.81 on
    its up axis.
    """

    t: np.ndarray
    """Timestamps, int64 microseconds (IMU clock)."""
    acc: np.ndarray
    """Specific force, float64 (N, 3), m/s^2, body frame."""
    gyro: np.ndarray
    """Angular rate, float64 (N, 3), rad/s, body frame."""

    @classmethod
    def from_arrays(cls, t, acc, gyro) -> "ImuSamples":
        t = np.ascontiguousarray(t, dtype=np.int64)
        acc = np.ascontiguousarray(acc, dtype=np.float64).reshape(-1, 3)
        gyro = np.ascontiguousarray(gyro, dtype=np.float64).reshape(-1, 3)
        if not (t.shape[0] == acc.shape[0] == gyro.shape[0]):
            raise ValueError(f"IMU columns differ in length: {t.shape[0]}, {acc.shape[0]}, {gyro.shape[0]}")
        return cls(t, acc, gyro)

    @classmethod
    def empty(cls) -> "ImuSamples":
        return cls.from_arrays(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3)))

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __getitem__(self, index) -> "ImuSamples":
        return ImuSamples(self.t[index], self.acc[index], self.gyro[index])

    @property
    def rate_hz(self) -> float:
        """Median sample rate in Hz (0 for fewer than two samples)."""
        if len(self) < 2:
            return 0.0
        return float(1e6 / np.median(np.diff(self.t)))

    def time_window(self, t0_us: int, t1_us: int) -> "ImuSamples":
        return self[window_slice(self.t, t0_us, t1_us)]

    def validate(self, source: str | None = None) -> None:
        if len(self) == 0:
            return
        check_series(self.t, np.isfinite(self.acc).all(axis=1) & np.isfinite(self.gyro).all(axis=1), source, "IMU sample")
        # Far beyond any IMU's range (MEMS parts saturate at 16-32 g and 35-70 rad/s): a unit or scale error, which
        # would otherwise end in an indeterminate factor graph.
        for name, values, limit, unit in (("acceleration", self.acc, MAX_ACCELERATION, "m/s^2"), ("angular rate", self.gyro, MAX_ANGULAR_RATE, "rad/s")):
            mag = np.hypot.reduce(values, axis=1)  # np.linalg.norm overflowed on 1e300, with numpy's warning on stderr
            bad = np.flatnonzero(mag > limit)
            if bad.size:
                i = int(bad[0])
                raise InputError(source, f"{name} {mag[i]:.3g} {unit} is beyond any IMU's range (limit {limit:g} {unit}; wrong units?)",
                                 f"IMU sample {i}")

    def covers(self, t0_us: int, t1_us: int) -> bool:
        """Whether samples lie at or before ``t0_us`` and at or after ``t1_us`` (IMU clock)."""
        return len(self) > 0 and int(self.t[0]) <= t0_us and int(self.t[-1]) >= t1_us
