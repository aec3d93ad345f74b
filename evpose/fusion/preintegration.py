"""IMU buffering and gtsam combined preintegration between two camera-clock times.

The buffer holds every IMU sample received (on the camera clock:
``t_cam = t_imu - time_offset_us``). Integration between arbitrary times
splits the span at the sample times and uses the measurement linearly
interpolated at each piece's midpoint, which is second-order accurate for
smooth motion and exact at the span ends (registrations do not fall on IMU
samples). Beyond the last sample the last measurement is held.
"""

from __future__ import annotations

import itertools

import numba as nb
import numpy as np

from evpose.core.imu import ImuSamples
from evpose.errors import InputError
from evpose.fusion.config import FusionConfig


def make_preintegration_params(config: FusionConfig, T_cam_imu: np.ndarray | None = None):
    """gtsam ``PreintegrationCombinedParams`` for a z-up world from the config's noise densities.

    The IMU body is the estimated frame, so ``body_P_sensor`` stays identity; the
    camera extrinsic is applied by the backends when they convert poses.
    """
    import gtsam

    p = gtsam.PreintegrationCombinedParams.MakeSharedU(config.gravity)
    eye = np.eye(3)
    p.setAccelerometerCovariance(eye * config.accel_noise_density**2)
    p.setGyroscopeCovariance(eye * config.gyro_noise_density**2)
    p.setBiasAccCovariance(eye * config.accel_bias_random_walk**2)
    p.setBiasOmegaCovariance(eye * config.gyro_bias_random_walk**2)
    p.setIntegrationCovariance(eye * config.integration_sigma**2)
    return p


_VERSIONS = itertools.count()


class ImuBuffer:
    """All IMU samples received so far, on the camera clock, with piecewise integration."""

    def __init__(self, time_offset_us: int = 0):
        self.time_offset_us = int(time_offset_us)
        # Samples live in arrays with spare capacity (doubled when full): appending a step's few samples costs
        # the same however long the run, where re-concatenating the whole buffer grew with it. Only indices
        # >= the count are ever written, so the views handed out by ``samples`` (kept by snapshots) never change.
        self._t = np.zeros(0, np.int64)
        self._acc = np.zeros((0, 3))
        self._gyro = np.zeros((0, 3))
        self._n = 0
        self._view: ImuSamples = ImuSamples.empty()
        self.version = next(_VERSIONS)
        """Changes whenever the buffered samples change, unique across buffers (keys caches of integrals over them)."""
        self._measured: tuple | None = None
        """(version, integer time, acc, gyro) of the last integer-time :meth:`measurement_at` (read-only arrays)."""

    def add(self, imu: ImuSamples) -> None:
        """Append samples given on the IMU clock; samples not newer than the last one kept are ignored (overlapping chunks)."""
        if len(imu) == 0:
            return
        t = imu.t.astype(np.int64) - self.time_offset_us
        if not _valid_chunk(t, imu.acc, imu.gyro):  # one pass; _reject names the first bad sample
            self._reject(imu, t)
        # t increases, so the samples newer than the last kept one are a suffix.
        first = 0 if self._n == 0 else int(np.searchsorted(t, self._t[self._n - 1], side="right"))
        if first >= t.shape[0]:
            return
        n = self._n + t.shape[0] - first
        if n > self._t.shape[0]:
            cap = max(n, 2 * self._t.shape[0], 64)
            for name, dtype in (("_t", np.int64), ("_acc", np.float64), ("_gyro", np.float64)):
                old = getattr(self, name)
                grown = np.empty((cap,) + old.shape[1:], dtype)
                grown[: self._n] = old[: self._n]
                setattr(self, name, grown)
        self._t[self._n : n] = t[first:]
        self._acc[self._n : n] = imu.acc[first:]
        self._gyro[self._n : n] = imu.gyro[first:]
        self._n = n
        self._view = ImuSamples(self._t[:n], self._acc[:n], self._gyro[:n])
        self.version = next(_VERSIONS)

    @staticmethod
    def _reject(imu: ImuSamples, t: np.ndarray) -> None:
        if not (np.isfinite(imu.acc).all() and np.isfinite(imu.gyro).all()):
            bad = int(np.flatnonzero(~(np.isfinite(imu.acc).all(1) & np.isfinite(imu.gyro).all(1)))[0])
            raise InputError(None, "NaN or infinite value", f"IMU sample {bad}")
        i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise InputError(None, f"timestamp {int(imu.t[i])} us does not increase", f"IMU sample {i}")

    @property
    def samples(self) -> ImuSamples:
        return self._view

    @property
    def t_last_us(self) -> int | None:
        return int(self._t[self._n - 1]) if self._n else None

    def __len__(self) -> int:
        return self._n

    def set_samples(self, samples: ImuSamples) -> None:
        """Replace the buffer with samples already on the camera clock (used by restore)."""
        # Adopted without a copy and without spare capacity: the next add reallocates, so nothing written
        # later can reach arrays the caller (e.g. a snapshot shared with another buffer) still holds.
        self._t, self._acc, self._gyro = samples.t, samples.acc, samples.gyro
        self._n = len(samples)
        self._view = samples
        self.version = next(_VERSIONS)

    def measurement_at(self, t_us: float) -> tuple[np.ndarray, np.ndarray]:
        """Linearly interpolated (acc, gyro) at a time; held constant outside the buffered span (read-only arrays at an
        integer time: they are kept for the next call)."""
        s = self.samples
        if len(s) == 0:
            return np.zeros(3), np.zeros(3)
        if isinstance(t_us, (int, np.integer)):
            # Every update asks twice for the same time (prediction and new state): the last answer is kept (read-only,
            # a pure function of the samples and the time); else one compiled call for the numpy lines below, the
            # same operations on the same values (integer time difference, then one float division).
            last = self._measured
            if last is not None and last[0] == self.version and last[1] == t_us:
                return last[2], last[3]
            acc, gyro = np.empty(3), np.empty(3)
            _measurement_kernel(s.t, s.acc, s.gyro, np.int64(t_us), acc, gyro)
            acc.setflags(write=False)
            gyro.setflags(write=False)
            self._measured = (self.version, int(t_us), acc, gyro)
            return acc, gyro
        i = int(np.searchsorted(s.t, t_us, side="right"))
        if i <= 0:
            return s.acc[0].copy(), s.gyro[0].copy()
        if i >= len(s):
            return s.acc[-1].copy(), s.gyro[-1].copy()
        a = (t_us - s.t[i - 1]) / float(s.t[i] - s.t[i - 1])
        return (1 - a) * s.acc[i - 1] + a * s.acc[i], (1 - a) * s.gyro[i - 1] + a * s.gyro[i]

    def pieces(self, t0_us: int, t1_us: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Split ``[t0, t1]`` at sample times: durations (s), acc and gyro per piece (midpoint values)."""
        s = self.samples
        if t1_us <= t0_us:
            return np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
        if len(s) == 0:
            raise InputError(None, "no IMU samples to integrate", f"span {t0_us}..{t1_us} us")
        i0 = int(np.searchsorted(s.t, t0_us, side="right"))
        i1 = int(np.searchsorted(s.t, t1_us, side="left"))
        # Interpolate on the samples bracketing [t0, t1] only (t[lo] <= t0, t[hi - 1] >= t1): the same
        # brackets, so the same values as over the whole buffer, at a cost that does not grow with it.
        lo, hi = max(i0 - 1, 0), min(i1 + 1, len(s))
        n = i1 - i0 + 1
        dts, acc, gyro = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        _pieces_kernel(s.t, s.acc, s.gyro, int(t0_us), int(t1_us), i0, i1, lo, hi, dts, acc, gyro)
        return dts, acc, gyro

    def integrate(self, pim, t0_us: int, t1_us: int) -> None:
        """Add the IMU motion of ``[t0, t1]`` (camera clock) to a gtsam preintegration object.

        gtsam rotates each piece's specific force by the attitude at the piece's
        *start*, a first-order error of ``|f| |omega| dt / 2`` per piece (1e-3 m/s
        over 0.4 s at 500 Hz with gravity in ``f``). We hand it the force rotated
        to the piece's middle instead, ``ba + Exp(omega dt / 2)(f - ba)``, which
        makes the scheme second order at no cost.
        """
        if t1_us <= t0_us:
            return
        s = self.samples
        if len(s) == 0:
            raise InputError(None, "no IMU samples to integrate", f"span {t0_us}..{t1_us} us")
        bias = pim.biasHat()
        # :meth:`pieces`, then ``ba + rotate_half_step(gyro - bg, dts, acc - ba)``, in one compiled call: the same
        # operations on the same values (~10 numpy calls and their arrays fewer per integral).
        dts, acc, gyro = _midpoint_pieces(s.t, s.acc, s.gyro, np.int64(t0_us), np.int64(t1_us),
                                          np.asarray(bias.accelerometer(), np.float64), np.asarray(bias.gyroscope(), np.float64))
        for k in range(dts.shape[0]):
            if dts[k] > 0:
                pim.integrateMeasurement(acc[k], gyro[k], float(dts[k]))


@nb.njit(cache=True)
def _measurement_kernel(t, acc_s, gyro_s, t_us, acc, gyro):
    """:meth:`ImuBuffer.measurement_at` at an integer time into ``acc`` / ``gyro`` (3,)."""
    n = t.shape[0]
    i = np.searchsorted(t, t_us, side="right")
    if i <= 0 or i >= n:
        j = 0 if i <= 0 else n - 1
        for k in range(3):
            acc[k] = acc_s[j, k]
            gyro[k] = gyro_s[j, k]
        return
    a = np.float64(t_us - t[i - 1]) / np.float64(t[i] - t[i - 1])
    for k in range(3):
        acc[k] = (1 - a) * acc_s[i - 1, k] + a * acc_s[i, k]
        gyro[k] = (1 - a) * gyro_s[i - 1, k] + a * gyro_s[i, k]


@nb.njit(cache=True)
def _valid_chunk(t, acc, gyro):
    """All measurements finite and timestamps strictly increasing (``ImuBuffer.add``'s checks in one pass)."""
    for i in range(t.shape[0]):
        for k in range(3):
            if not (np.isfinite(acc[i, k]) and np.isfinite(gyro[i, k])):
                return False
        if i > 0 and t[i] <= t[i - 1]:
            return False
    return True


@nb.njit(cache=True)
def _interp(x, xp, fp, k):
    """``np.interp(x, xp, fp[:, k])`` for one ``x``, step for step as numpy's C loop (binary search for
    ``xp[j] <= x < xp[j + 1]``, exact ends, the same slope and NaN fallbacks), so the values are bit-identical."""
    n = xp.shape[0]
    if n == 1:
        return fp[0, k]  # numpy: left / right default to the only value, and so does x == xp[0]
    if x != x:
        return x
    if x < xp[0]:
        return fp[0, k]
    if x > xp[n - 1]:
        return fp[n - 1, k]
    if x == xp[n - 1]:
        return fp[n - 1, k]
    a, b = 0, n - 1  # xp[a] <= x < xp[b]
    while b - a > 1:
        m = (a + b) >> 1
        if xp[m] <= x:
            a = m
        else:
            b = m
    j = a
    if xp[j] == x:
        return fp[j, k]
    slope = (fp[j + 1, k] - fp[j, k]) / (xp[j + 1] - xp[j])
    r = slope * (x - xp[j]) + fp[j, k]
    if r != r:
        r = slope * (x - xp[j + 1]) + fp[j + 1, k]
        if r != r and fp[j, k] == fp[j + 1, k]:
            r = fp[j, k]
    return r


@nb.njit(cache=True)
def _pieces_kernel(t, acc_s, gyro_s, t0, t1, i0, i1, lo, hi, dts, acc, gyro):
    """:meth:`ImuBuffer.pieces` in one pass: bounds ``[t0, t[i0:i1], t1]`` (as float64), piece durations in s and the
    samples in ``[lo, hi)`` interpolated at the piece midpoints (the numpy version: ~15 array operations per call)."""
    ts = t[lo:hi].astype(np.float64)
    fa = acc_s[lo:hi]
    fg = gyro_s[lo:hi]
    n = dts.shape[0]
    prev = np.float64(t0)
    for i in range(n):
        nxt = np.float64(t1) if i == n - 1 else np.float64(t[i0 + i])
        mid = 0.5 * (prev + nxt)
        dts[i] = (nxt - prev) * 1e-6
        for k in range(3):
            acc[i, k] = _interp(mid, ts, fa, k)
            gyro[i, k] = _interp(mid, ts, fg, k)
        prev = nxt


@nb.njit(cache=True)
def rotate_half_step(omega: np.ndarray, dts: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """``Exp(omega * dt / 2) @ vec`` row by row (Rodrigues), for the midpoint correction (numba: a few pieces per call)."""
    out = np.empty_like(vec)
    for i in range(vec.shape[0]):
        t0 = omega[i, 0] * 0.5 * dts[i]
        t1 = omega[i, 1] * 0.5 * dts[i]
        t2 = omega[i, 2] * 0.5 * dts[i]
        v0, v1, v2 = vec[i, 0], vec[i, 1], vec[i, 2]
        ang = np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if ang < 1e-12:
            out[i, 0] = v0 + t1 * v2 - t2 * v1
            out[i, 1] = v1 + t2 * v0 - t0 * v2
            out[i, 2] = v2 + t0 * v1 - t1 * v0
            continue
        k0, k1, k2 = t0 / ang, t1 / ang, t2 / ang
        c, sn = np.cos(ang), np.sin(ang)
        kd = k0 * v0 + k1 * v1 + k2 * v2
        out[i, 0] = v0 * c + (k1 * v2 - k2 * v1) * sn + k0 * kd * (1.0 - c)
        out[i, 1] = v1 * c + (k2 * v0 - k0 * v2) * sn + k1 * kd * (1.0 - c)
        out[i, 2] = v2 * c + (k0 * v1 - k1 * v0) * sn + k2 * kd * (1.0 - c)
    return out


@nb.njit(cache=True)
def _midpoint_pieces(t, acc_s, gyro_s, t0, t1, ba, bg):
    """(durations s, midpoint-rotated forces, midpoint gyro) of ``[t0, t1]`` (``t1 > t0``, samples not empty) for
    :meth:`ImuBuffer.integrate`: :meth:`ImuBuffer.pieces`' indices and kernel, then ``ba + rotate_half_step(gyro - bg,
    dts, acc - ba)`` element by element."""
    n_s = t.shape[0]
    i0 = np.searchsorted(t, t0, side="right")
    i1 = np.searchsorted(t, t1, side="left")
    lo, hi = max(i0 - 1, 0), min(i1 + 1, n_s)
    n = i1 - i0 + 1
    dts, acc, gyro = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
    _pieces_kernel(t, acc_s, gyro_s, t0, t1, i0, i1, lo, hi, dts, acc, gyro)
    omega = np.empty((n, 3))
    force = np.empty((n, 3))
    for i in range(n):
        for k in range(3):
            omega[i, k] = gyro[i, k] - bg[k]
            force[i, k] = acc[i, k] - ba[k]
    rotated = rotate_half_step(omega, dts, force)
    for i in range(n):
        for k in range(3):
            rotated[i, k] = ba[k] + rotated[i, k]
    return dts, rotated, gyro


def preintegrate(buffer: ImuBuffer, params, bias, t0_us: int, t1_us: int):
    """A fresh ``PreintegratedCombinedMeasurements`` over ``[t0, t1]`` with the given bias linearisation point."""
    import gtsam

    pim = gtsam.PreintegratedCombinedMeasurements(params, bias)
    buffer.integrate(pim, t0_us, t1_us)
    return pim
