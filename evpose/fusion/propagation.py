"""IMU propagation of a navigation state with gtsam ``NavState.predict``: the sub-millisecond pose between registrations.

A :class:`NavPropagator` is anchored at one estimated state (time, NavState,
bias). ``predict(t)`` integrates the buffered IMU from the anchor to ``t``.
"""

from __future__ import annotations

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.fusion.preintegration import ImuBuffer
from evpose.fusion.state import Extrinsic, FusedState


class NavPropagator:
    """Propagates one anchored IMU-body state forward with the buffered IMU."""

    def __init__(self, buffer: ImuBuffer, params, extrinsic: Extrinsic):
        self.buffer = buffer
        self.params = params
        self.extrinsic = extrinsic
        self.t_us: int | None = None
        self.nav = None
        self.bias = None
        self._cache_key = None
        self._cache_pim = None
        self._cache_state_key = None
        self._cache_state: FusedState | None = None
        self._cache_nav_key = None
        self._cache_nav = None

    def anchor(self, t_us: int, nav, bias) -> None:
        """Restart propagation from a new estimated state."""
        self.t_us = int(t_us)
        self.nav = nav
        self.bias = bias
        self._cache_key = None
        self._cache_pim = None
        self._cache_state_key = None
        self._cache_state = None
        self._cache_nav_key = None
        self._cache_nav = None

    def preintegration_to(self, t_us: int):
        """A fresh preintegration from the anchor to ``t_us``.

        Built from scratch on every call (~2 us per IMU sample): copying a gtsam
        preintegration costs ~170 us, more than re-integrating the few samples
        between two registrations, and from-scratch keeps results independent
        of the call history.
        """
        import gtsam

        # One tracker update asks for the same span up to three times (motion prediction, polarity
        # prediction, the new graph state); the integral is a pure function of the anchor, the buffer
        # and t, so the last one is reused while none of them changed (callers only read it).
        key = (self.buffer.version, int(t_us))
        if self._cache_key == key:
            return self._cache_pim
        pim = gtsam.PreintegratedCombinedMeasurements(self.params, self.bias)
        self.buffer.integrate(pim, self.t_us, int(t_us))
        self._cache_key, self._cache_pim = key, pim
        return pim

    def predict_nav(self, t_us: int):
        if t_us <= self.t_us:
            return self.nav
        # The motion prediction and the new graph state's initial value ask for the same NavState each update:
        # like the integral, a pure function of the anchor, the buffer and t (NavState is an immutable value).
        key = (self.buffer.version, int(t_us))
        if self._cache_nav_key != key:
            self._cache_nav = self.preintegration_to(t_us).predict(self.nav, self.bias)
            self._cache_nav_key = key
        return self._cache_nav

    def fused_state(self, t_us: int, nav, bias, covariance_imu=None, degraded: bool = False) -> FusedState:
        """Camera-frame FusedState from an IMU-body NavState."""
        T_wi = nav.pose().matrix()
        acc_m, gyro_m = self.buffer.measurement_at(t_us)
        gyro_bias = np.array(bias.gyroscope(), dtype=np.float64)  # asked once, copied (gtsam hands out a view into the bias)
        omega_imu = gyro_m - gyro_bias
        R_wi = T_wi[:3, :3]
        v_cam = self.extrinsic.cam_velocity(R_wi, np.asarray(nav.velocity(), dtype=np.float64), omega_imu)
        cov = None if covariance_imu is None else self.extrinsic.cam_covariance(covariance_imu)
        return FusedState(int(t_us), self.extrinsic.cam_pose(T_wi), v_cam, np.array(bias.accelerometer(), dtype=np.float64),
                          gyro_bias, cov, bool(degraded), self.extrinsic.cam_omega(omega_imu))

    def predict(self, t_us: int, degraded: bool = False) -> FusedState:
        """The state propagated to ``t_us`` (a copy: the caller may modify it)."""
        return self.predict_view(t_us, degraded).copy()

    def predict_view(self, t_us: int, degraded: bool = False) -> FusedState:
        """:meth:`predict` without the copy: the cached state itself, which the caller must not modify."""
        # The motion model and the polarity selector both ask for the same time each update: reuse the
        # state while the anchor and the buffer are unchanged (each reads a part of it, none writes).
        key = (self.buffer.version, int(t_us), bool(degraded))
        if self._cache_state_key != key:
            self._cache_state = self.fused_state(t_us, self.predict_nav(t_us), self.bias, None, degraded)
            self._cache_state_key = key
        return self._cache_state


def imu_rate_trajectory(history, buffer: ImuBuffer, params, extrinsic: Extrinsic, t0_us: int, t1_us: int) -> Trajectory:
    """Camera poses at every IMU sample time in ``[t0, t1)``, each propagated from the latest state at or before it.

    ``history`` is a time-sorted list of ``(t_us, NavState, bias)`` anchors.
    Times before the first anchor are skipped.
    """
    s = buffer.samples
    if not history or len(s) == 0:
        return Trajectory.empty()
    ts = s.t[(s.t >= t0_us) & (s.t < t1_us)]
    ts = ts[ts >= history[0][0]]
    if ts.size == 0:
        return Trajectory.empty()
    anchors_t = np.array([h[0] for h in history], dtype=np.int64)
    which = np.searchsorted(anchors_t, ts, side="right") - 1
    mats = np.empty((ts.size, 4, 4))
    prop = NavPropagator(buffer, params, extrinsic)
    current = -1
    for k in range(ts.size):
        if which[k] != current:
            current = int(which[k])
            prop.anchor(*history[current])
        mats[k] = extrinsic.cam_pose(prop.predict_nav(int(ts[k])).pose().matrix())
    return Trajectory.from_matrices(ts, mats)
