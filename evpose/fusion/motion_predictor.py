"""Adapter: any fusion backend as the tracker's ``MotionPredictor`` (reset / predict / update / snapshot / restore).

The tracker's predictor protocol only reports successful registrations. The
adapter adds :meth:`report`, which the fused modes call once per step with the
registration result (or ``None`` when it failed) and its covariance, so the
backend can mark degraded poses; ``update`` is ``report`` without covariance.
"""

from __future__ import annotations

import numpy as np

from evpose.core.imu import ImuSamples
from evpose.fusion.revision_readout import moved_like
from evpose.fusion.state import FusedState


class FusionMotionPredictor:
    """Predicts the camera pose with IMU propagation from the fused state."""

    def __init__(self, fusion, imu: ImuSamples | None = None, initial_velocity_world: np.ndarray | None = None):
        self.fusion = fusion
        if imu is not None:
            fusion.add_imu(imu)
        self.initial_velocity_world = initial_velocity_world
        self.initial_biases: tuple[np.ndarray, np.ndarray] | None = None
        """(accelerometer, gyroscope) biases, IMU frame, the backend starts from at the next :meth:`reset`; None: zero,
        as at a session's start (a restart after an event gap without ground truth carries the last estimates over:
        ``restart_gate.carry_biases``)."""
        self.last: FusedState | None = None
        self.input_log: list | None = None
        """When a list, every :meth:`report` appends ``(t_us, T_world_cam or None, covariance or None)`` to it: the
        fusion's inputs, for offline studies (:mod:`evpose.fusion.replay`). Not part of the snapshot state."""

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        if self.initial_biases is None:
            self.last = self.fusion.initialize(int(t_us), T_world_cam, self.initial_velocity_world)
        else:
            ba, bg = self.initial_biases
            self.last = self.fusion.initialize(int(t_us), T_world_cam, self.initial_velocity_world,
                                               acc_bias=ba, gyro_bias=bg)

    def predict(self, t_us: int) -> np.ndarray:
        # The pose alone: a copy of it, not of the whole propagated state, where the backend shares its cache.
        view = getattr(self.fusion, "predict_view", None)
        T = view(int(t_us)).T_world_cam.copy() if view is not None else self.fusion.predict(int(t_us)).T_world_cam
        last = self.last
        if last is not None and last.readout_T_world_cam is not None and getattr(self.fusion.config, "revision_readout_prior", False):
            # The read-out's correction of the last state carried onto the prediction (FusionConfig.revision_readout_prior).
            T = moved_like(T, last.T_world_cam, last.readout_T_world_cam)
        return T

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self.report(t_us, T_world_cam, None)

    def report(self, t_us: int, T_world_cam: np.ndarray | None, covariance_6x6: np.ndarray | None) -> FusedState:
        """Fuse one step's registration (``None`` = failed) and return the fused state."""
        if self.input_log is not None:
            self.input_log.append((int(t_us), None if T_world_cam is None else np.array(T_world_cam, np.float64),
                                   None if covariance_6x6 is None else np.array(covariance_6x6, np.float64)))
        self.last = self.fusion.update(int(t_us), T_world_cam, covariance_6x6)
        return self.last

    def snapshot(self) -> dict:
        return {"fusion": self.fusion.snapshot(), "last": None if self.last is None else self.last.copy()}

    def restore(self, state: dict) -> None:
        self.fusion.restore(state["fusion"])
        self.last = None if state["last"] is None else state["last"].copy()
