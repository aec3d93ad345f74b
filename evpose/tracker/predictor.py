"""Motion predictors: where the camera is expected at the next update (culling and registration start).

The tracker calls ``predict(t)`` before each registration and ``update(t, T)``
after a successful one. In ``stpe`` mode a constant-velocity model does this;
fused modes plug an IMU-driven predictor with the same three methods in.
"""

from __future__ import annotations

from typing import Protocol

import gtsam
import numpy as np


class MotionPredictor(Protocol):
    """What the tracker needs from a motion model."""

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None: ...

    def predict(self, t_us: int) -> np.ndarray: ...

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None: ...

    def snapshot(self) -> dict: ...

    def restore(self, state: dict) -> None: ...


class ConstantPosePredictor:
    """The next pose is the last accepted one."""

    def __init__(self):
        self._t: int | None = None
        self._T: np.ndarray | None = None

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self._t, self._T = int(t_us), np.array(T_world_cam, dtype=np.float64)

    def predict(self, t_us: int) -> np.ndarray:
        if self._T is None:
            raise RuntimeError("predictor used before reset()")
        return self._T.copy()

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self.reset(t_us, T_world_cam)

    def snapshot(self) -> dict:
        return {"t": self._t, "T": None if self._T is None else self._T.copy()}

    def restore(self, state: dict) -> None:
        self._t = state["t"]
        self._T = None if state["T"] is None else state["T"].copy()


class ConstantVelocityPredictor:
    """Extrapolate the body-frame twist between the last two accepted poses (SE(3) log/exp, gtsam)."""

    def __init__(self, max_extrapolation_s: float = 0.1):
        self.max_extrapolation_s = float(max_extrapolation_s)
        """Do not extrapolate further than this past the last accepted pose (a long gap makes velocity stale), seconds."""
        self._hist: list[tuple[int, np.ndarray]] = []

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self._hist = [(int(t_us), np.array(T_world_cam, dtype=np.float64))]

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self._hist = (self._hist + [(int(t_us), np.array(T_world_cam, dtype=np.float64))])[-2:]

    def twist(self) -> np.ndarray:
        """Body-frame twist (rotation, translation) per second from the last two poses; zeros if only one."""
        if len(self._hist) < 2:
            return np.zeros(6)
        (t0, T0), (t1, T1) = self._hist
        if t1 <= t0:
            return np.zeros(6)
        rel = gtsam.Pose3(T0).between(gtsam.Pose3(T1))
        return gtsam.Pose3.Logmap(rel) / ((t1 - t0) * 1e-6)

    def predict(self, t_us: int) -> np.ndarray:
        if not self._hist:
            raise RuntimeError("predictor used before reset()")
        t1, T1 = self._hist[-1]
        dt = min(max((int(t_us) - t1) * 1e-6, 0.0), self.max_extrapolation_s)
        if len(self._hist) < 2 or dt == 0.0:
            return T1.copy()
        return gtsam.Pose3(T1).compose(gtsam.Pose3.Expmap(self.twist() * dt)).matrix()

    def snapshot(self) -> dict:
        return {"hist": [(t, T.copy()) for t, T in self._hist]}

    def restore(self, state: dict) -> None:
        self._hist = [(t, T.copy()) for t, T in state["hist"]]
