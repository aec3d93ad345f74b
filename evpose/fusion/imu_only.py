"""IMU-only dead reckoning baseline: integrate from the initial state, ignore every registration.

Each update chains one gtsam preintegration from the previous update's state
(biases fixed at their initial values), so the cost per update stays
constant however long the run. Every output is marked ``degraded``: no
registration ever supports it.
"""

from __future__ import annotations

import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory
from evpose.fusion.config import FusionConfig
from evpose.fusion.preintegration import ImuBuffer, make_preintegration_params
from evpose.fusion.propagation import NavPropagator, imu_rate_trajectory
from evpose.fusion.state import Extrinsic, FusedState


class ImuOnlyPropagator:
    """Dead reckoning with the same interface as the fusion backends."""

    def __init__(self, config: FusionConfig | None = None, calibration: CameraCalibration | None = None):
        self.config = config or FusionConfig()
        self.config.validate()
        self.time_offset_us = 0 if calibration is None else int(calibration.time_offset_us)
        self.extrinsic = Extrinsic(np.eye(4) if calibration is None else calibration.T_cam_imu)
        self.params = make_preintegration_params(self.config)
        self.buffer = ImuBuffer(self.time_offset_us)
        self.propagator = NavPropagator(self.buffer, self.params, self.extrinsic)
        self.history: list[tuple] = []

    def initialize(self, t_us: int, T_world_cam: np.ndarray, velocity_world=None, acc_bias=None, gyro_bias=None) -> FusedState:
        import gtsam

        z = np.zeros(3)
        ba = z if acc_bias is None else np.asarray(acc_bias, np.float64).reshape(3)
        bg = z if gyro_bias is None else np.asarray(gyro_bias, np.float64).reshape(3)
        T_wi = self.extrinsic.imu_pose(np.asarray(T_world_cam, np.float64).reshape(4, 4))
        v_cam = z if velocity_world is None else np.asarray(velocity_world, np.float64).reshape(3)
        _, gyro_m = self.buffer.measurement_at(t_us)
        v = self.extrinsic.imu_velocity(T_wi[:3, :3], v_cam, gyro_m - bg)
        nav = gtsam.NavState(gtsam.Pose3(T_wi), v)
        bias = gtsam.imuBias.ConstantBias(ba, bg)
        self.propagator.anchor(int(t_us), nav, bias)
        self.history = [(int(t_us), nav, bias)]
        return self.propagator.fused_state(int(t_us), nav, bias, None, degraded=True)

    def add_imu(self, imu: ImuSamples) -> None:
        self.buffer.add(imu)

    def update(self, t_us: int, T_world_cam_measured: np.ndarray | None = None, covariance_6x6: np.ndarray | None = None) -> FusedState:
        """Propagate to ``t_us``; the measurement is ignored by design."""
        if self.propagator.t_us is None:
            raise RuntimeError("ImuOnlyPropagator.update called before initialize")
        t_us = int(t_us)
        if t_us <= self.propagator.t_us:
            raise ValueError(f"update time {t_us} us is not after the last state at {self.propagator.t_us} us")
        nav = self.propagator.predict_nav(t_us)
        bias = self.propagator.bias
        self.propagator.anchor(t_us, nav, bias)
        self.history.append((t_us, nav, bias))
        if len(self.history) > self.config.window_states + 2:
            del self.history[0]
        return self.propagator.fused_state(t_us, nav, bias, None, degraded=True)

    def predict(self, t_us: int) -> FusedState:
        return self.propagator.predict(int(t_us), degraded=True)

    def imu_rate_poses(self, t0_us: int, t1_us: int) -> Trajectory:
        return imu_rate_trajectory(self.history, self.buffer, self.params, self.extrinsic, int(t0_us), int(t1_us))

    def snapshot(self) -> dict:
        # gtsam NavState / ConstantBias are immutable value types, safe to share.
        p = self.propagator
        return {"anchor": (p.t_us, p.nav, p.bias), "history": list(self.history), "imu": self.buffer.samples}

    def restore(self, snap: dict) -> None:
        self.buffer = ImuBuffer(self.time_offset_us)
        self.buffer.set_samples(snap["imu"])
        self.propagator = NavPropagator(self.buffer, self.params, self.extrinsic)
        t, nav, bias = snap["anchor"]
        if t is not None:
            self.propagator.anchor(t, nav, bias)
        self.history = list(snap["history"])
