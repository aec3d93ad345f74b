"""Error-state EKF baseline: the same inputs as the factor graph (IMU + registration poses + covariances).

Nominal state: IMU-body rotation ``R`` and position ``p`` in the world,
world velocity ``v``, accelerometer and gyroscope biases. Error state (15):
``[dtheta (body, right perturbation), dp (world), dv (world), dba, dbg]``, so
the pose block maps to gtsam's (rotation, translation) body-frame tangent by
``dp_body = R^T dp``. Propagation is first order per IMU piece (the same
midpoint pieces the factor graph integrates); the registration update uses
``r = (Log(R^T R_m), R^T (p_m - p))`` with Huber/Cauchy re-weighting of the
innovation (inflating its covariance), Joseph-form covariance update.
Unlike the graph it never revisits a past linearisation point (the weakness
the comparison measures).

Session 13, closed loop, the 2 s landing from ground truth, ATE mm / ARE deg
(346x260 seeds 0-3, 4-7, 8-11; 240x180 the same): the EKF 6.58 / 6.00 / 5.96,
7.31 / 8.54 / 8.33 mm, 0.0692 / 0.0674 / 0.0634, 0.0769 / 0.0893 / 0.0867 deg
(mean 7.120 / 0.0755), the graph 6.38 / 5.91 / 6.15, 7.25 / 8.48 / 8.43 mm,
0.0655 / 0.0676 / 0.0637, 0.0760 / 0.0875 / 0.0887 deg (mean 7.102 / 0.0748);
the textured landing (seed 0, 346x260) 7.32 against 7.43 mm; the demo landing
9.79 mm / 0.107 deg against 9.71 / 0.104. The newest state of the fixed-lag
smoother is the filter's estimate, the graph's robust kernel never engages
there and relinearising more did not help, so the two differ by linearisation
and the graph's constant-velocity prior only (without it the graph's mean is
7.103 / 0.0758): which one wins a set is not a property of either.

Session 29: on the same recorded registrations (each graph run's inputs replayed through both) the two differ by
-0.008 mm on 346x260 seeds 0-7 (5.297 / 5.305 mm), +0.004 on seeds 8-11, -0.008 at 240x180 (6.930 / 6.938) and
-0.010 on the 3 s landings (12.275 / 12.285), their estimates 0.03-0.06 mm RMS apart (0.36 mm on the 3 s landings'
turns), while a closed-loop pair moves by ~0.2 mm per seed whichever estimator runs (a neutral nudge of the graph
alone does the same): see :mod:`evpose.bench.fusion_regimes` and its ``same_inputs_gap``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory, skew
from evpose.fusion.config import FusionConfig, RobustLoss
from evpose.fusion.factor_graph import initial_bias_covariance, registration_covariance, usable_pose
from evpose.fusion.startup import gyro_bias_release_due, initial_gyro_bias_sigma, startup_inflated
from evpose.fusion.preintegration import ImuBuffer
from evpose.fusion.state import Extrinsic, FusedState


def _exp(w: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(w).as_matrix()


def _log(R: np.ndarray) -> np.ndarray:
    return Rotation.from_matrix(R).as_rotvec()


class _Nominal:
    """Nominal IMU-body state; plain arrays so copies are cheap."""

    __slots__ = ("t_us", "R", "p", "v", "ba", "bg", "P")

    def __init__(self, t_us, R, p, v, ba, bg, P):
        self.t_us, self.R, self.p, self.v, self.ba, self.bg, self.P = int(t_us), R, p, v, ba, bg, P

    def copy(self) -> "_Nominal":
        return _Nominal(self.t_us, np.copy(self.R), np.copy(self.p), np.copy(self.v), np.copy(self.ba), np.copy(self.bg), np.copy(self.P))


class ErrorStateEkf:
    """Error-state EKF fusion of registration poses with the IMU (baseline for the factor graph)."""

    def __init__(self, config: FusionConfig | None = None, calibration: CameraCalibration | None = None):
        self.config = config or FusionConfig()
        self.config.validate()
        self.time_offset_us = 0 if calibration is None else int(calibration.time_offset_us)
        self.extrinsic = Extrinsic(np.eye(4) if calibration is None else calibration.T_cam_imu)
        self.buffer = ImuBuffer(self.time_offset_us)
        self.g = np.array([0.0, 0.0, -self.config.gravity])
        self.state: _Nominal | None = None
        self.history: list[_Nominal] = []
        self.degraded = False
        self.start_us: int | None = None
        """Time of the state ``initialize`` set (``FusionConfig.registration_startup_s`` counts from it)."""
        self.hold_start_us: int | None = None
        """Start time of a running gyroscope-bias hold (``FusionConfig.gyro_bias_hold_s``); None: none or released."""

    # -------------------------------------------------------------- propagation
    def _propagate(self, s: _Nominal, t_us: int, with_covariance: bool = True) -> _Nominal:
        s = s.copy()
        c = self.config
        dts, acc, gyro = self.buffer.pieces(s.t_us, int(t_us))
        I3 = np.eye(3)
        for k in range(dts.shape[0]):
            dt = float(dts[k])
            a = acc[k] - s.ba
            w = gyro[k] - s.bg
            # Force rotated by the mid-piece attitude (second order, as the graph's preintegration).
            dRh = _exp(w * (0.5 * dt))
            dR = dRh @ dRh
            acc_w = s.R @ (dRh @ a) + self.g
            if with_covariance:
                F = np.eye(15)
                F[0:3, 0:3] = dR.T
                F[0:3, 12:15] = -I3 * dt
                F[3:6, 6:9] = I3 * dt
                F[6:9, 0:3] = -s.R @ skew(a) * dt
                F[6:9, 9:12] = -s.R * dt
                Q = np.zeros(15)
                Q[0:3] = c.gyro_noise_density**2 * dt
                Q[3:6] = c.integration_sigma**2 * dt
                Q[6:9] = c.accel_noise_density**2 * dt
                Q[9:12] = c.accel_bias_random_walk**2 * dt
                Q[12:15] = c.gyro_bias_random_walk**2 * dt
                s.P = F @ s.P @ F.T + np.diag(Q)
            s.p = s.p + s.v * dt + 0.5 * acc_w * dt * dt
            s.v = s.v + acc_w * dt
            s.R = s.R @ dR
        s.t_us = int(t_us)
        return s

    # ------------------------------------------------------------------ output
    def _fused(self, s: _Nominal, degraded: bool) -> FusedState:
        T_wi = np.eye(4)
        T_wi[:3, :3] = s.R
        T_wi[:3, 3] = s.p
        _, gyro_m = self.buffer.measurement_at(s.t_us)
        omega = gyro_m - s.bg
        # Pose covariance in gtsam's body-frame tangent: dp_body = R^T dp_world.
        J = np.zeros((6, 15))
        J[0:3, 0:3] = np.eye(3)
        J[3:6, 3:6] = s.R.T
        cov_imu = J @ s.P @ J.T
        return FusedState(s.t_us, self.extrinsic.cam_pose(T_wi), self.extrinsic.cam_velocity(s.R, s.v, omega), s.ba.copy(), s.bg.copy(),
                          self.extrinsic.cam_covariance(cov_imu), bool(degraded), self.extrinsic.cam_omega(omega))

    # -------------------------------------------------------------- public API
    def initialize(self, t_us: int, T_world_cam: np.ndarray, velocity_world=None, acc_bias=None, gyro_bias=None) -> FusedState:
        c = self.config
        z = np.zeros(3)
        ba = z.copy() if acc_bias is None else np.asarray(acc_bias, np.float64).reshape(3).copy()
        bg = z.copy() if gyro_bias is None else np.asarray(gyro_bias, np.float64).reshape(3).copy()
        T_wi = self.extrinsic.imu_pose(np.asarray(T_world_cam, np.float64).reshape(4, 4))
        v_cam = z if velocity_world is None else np.asarray(velocity_world, np.float64).reshape(3)
        _, gyro_m = self.buffer.measurement_at(t_us)
        v = self.extrinsic.imu_velocity(T_wi[:3, :3], v_cam, gyro_m - bg)
        sigma_v = c.init_sigma_velocity if velocity_world is not None else c.unknown_velocity_sigma
        P = np.diag([c.init_sigma_rot**2] * 3 + [c.init_sigma_trans**2] * 3 + [sigma_v**2] * 3
                    + [c.init_sigma_acc_bias**2] * 3 + [initial_gyro_bias_sigma(c) ** 2] * 3)
        bias_cov = initial_bias_covariance(c, T_wi[:3, :3])
        if bias_cov is not None:
            P[9:, 9:] = bias_cov
        self.state = _Nominal(int(t_us), T_wi[:3, :3].copy(), T_wi[:3, 3].copy(), v, ba, bg, P)
        self.history = [self.state.copy()]
        self.degraded = False
        self.hold_start_us = int(t_us) if c.gyro_bias_hold_s > 0 else None
        self.start_us = int(t_us)
        return self._fused(self.state, False)

    def add_imu(self, imu: ImuSamples) -> None:
        self.buffer.add(imu)

    def update(self, t_us: int, T_world_cam_measured: np.ndarray | None, covariance_6x6: np.ndarray | None = None) -> FusedState:
        if self.state is None:
            raise RuntimeError("ErrorStateEkf.update called before initialize")
        if int(t_us) <= self.state.t_us:
            raise ValueError(f"update time {t_us} us is not after the last state at {self.state.t_us} us")
        s = self._propagate(self.state, int(t_us))
        if gyro_bias_release_due(self.config, self.hold_start_us, int(t_us)):
            s.P[12:15, 12:15] += np.eye(3) * self.config.init_sigma_gyro_bias**2  # the held bias released (the graph's step)
            self.hold_start_us = None
        T_world_cam_measured = usable_pose(T_world_cam_measured)
        if T_world_cam_measured is None:
            self.degraded = True
        else:
            reacquire = self.degraded
            cov = startup_inflated(self.config, self.start_us, int(t_us), covariance_6x6)
            self._correct(s, np.asarray(T_world_cam_measured, np.float64).reshape(4, 4), cov, robust=not reacquire)
            self.degraded = False
        self.state = s
        self.history.append(s.copy())
        if len(self.history) > self.config.window_states + 2:
            del self.history[0]
        return self._fused(s, self.degraded)

    def _correct(self, s: _Nominal, T_meas_cam: np.ndarray, cov_cam, robust: bool) -> None:
        c = self.config
        T_m = self.extrinsic.imu_pose(T_meas_cam)
        Rm = self.extrinsic.imu_covariance(registration_covariance(c, cov_cam))
        r = np.concatenate([_log(s.R.T @ T_m[:3, :3]), s.R.T @ (T_m[:3, 3] - s.p)])
        H = np.zeros((6, 15))
        H[0:3, 0:3] = np.eye(3)
        H[3:6, 3:6] = s.R.T
        S = H @ s.P @ H.T + Rm
        if robust and c.registration_loss is not RobustLoss.NONE:
            # IRLS-style: a Huber/Cauchy weight on the innovation's Mahalanobis distance inflates its covariance.
            d = float(np.sqrt(r @ np.linalg.solve(S, r)))
            k = c.registration_loss_scale
            w = 1.0
            if c.registration_loss is RobustLoss.HUBER and d > k:
                w = k / d
            elif c.registration_loss is RobustLoss.CAUCHY:
                w = 1.0 / (1.0 + (d / k) ** 2)
            if w < 1.0:
                Rm = Rm / w
                S = H @ s.P @ H.T + Rm
        K = np.linalg.solve(S, H @ s.P).T
        dx = K @ r
        IKH = np.eye(15) - K @ H
        s.P = IKH @ s.P @ IKH.T + K @ Rm @ K.T
        s.P = 0.5 * (s.P + s.P.T)
        s.R = s.R @ _exp(dx[0:3])
        s.p = s.p + dx[3:6]
        s.v = s.v + dx[6:9]
        s.ba = s.ba + dx[9:12]
        s.bg = s.bg + dx[12:15]

    def predict(self, t_us: int) -> FusedState:
        if self.state is None:
            raise RuntimeError("ErrorStateEkf.predict called before initialize")
        if int(t_us) <= self.state.t_us:
            return self._fused(self.state, self.degraded)
        # Mean-only propagation keeps predict cheap; the covariance is reported at updates.
        out = self._fused(self._propagate(self.state, int(t_us), with_covariance=False), self.degraded)
        out.covariance = None
        return out

    def imu_rate_poses(self, t0_us: int, t1_us: int) -> Trajectory:
        s = self.buffer.samples
        if not self.history or len(s) == 0:
            return Trajectory.empty()
        ts = s.t[(s.t >= t0_us) & (s.t < t1_us)]
        ts = ts[ts >= self.history[0].t_us]
        if ts.size == 0:
            return Trajectory.empty()
        anchors_t = np.array([h.t_us for h in self.history], dtype=np.int64)
        which = np.searchsorted(anchors_t, ts, side="right") - 1
        mats = np.empty((ts.size, 4, 4))
        for k in range(ts.size):
            a = self.history[int(which[k])]
            st = self._propagate(a, int(ts[k]), with_covariance=False) if ts[k] > a.t_us else a
            T = np.eye(4)
            T[:3, :3] = st.R
            T[:3, 3] = st.p
            mats[k] = self.extrinsic.cam_pose(T)
        return Trajectory.from_matrices(ts, mats)

    def snapshot(self) -> dict:
        return {"state": None if self.state is None else self.state.copy(), "history": [h.copy() for h in self.history],
                "degraded": self.degraded, "imu": self.buffer.samples, "hold_start_us": self.hold_start_us,
                "start_us": self.start_us}

    def restore(self, snap: dict) -> None:
        self.state = None if snap["state"] is None else snap["state"].copy()
        self.history = [h.copy() for h in snap["history"]]
        self.degraded = bool(snap["degraded"])
        self.hold_start_us = snap.get("hold_start_us")
        self.start_us = snap.get("start_us")
        self.buffer = ImuBuffer(self.time_offset_us)
        self.buffer.set_samples(snap["imu"])
