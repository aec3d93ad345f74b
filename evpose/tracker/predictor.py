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
        return {"t": self._t, "T": None if self._T is None else np.copy(self._T)}

    def restore(self, state: dict) -> None:
        self._t = state["t"]
        self._T = None if state["T"] is None else np.copy(state["T"])


class ConstantVelocityPredictor:
    """Constant body-frame twist fitted to the recent accepted poses (SE(3) log/exp, gtsam).

    With ``window_us`` 0 the twist comes from the last two poses. A registration
    is noisy (~1 cm per 5 ms update on the simulated landing), and a two-pose
    velocity turns that noise into ~3 m/s of velocity error, which the next
    prediction, the registration's lag compensation and the pose prior all
    inherit: the track random-walks away. With a window, the poses of the last
    ``window_us`` (at most ``max_poses``) are expressed as tangent vectors at the
    newest one and a straight line ``xi(t) = a + b (t - t_last)`` is fitted by
    least squares: ``b`` is the twist and ``a`` a smoothed correction of the
    newest pose. A constant twist is reproduced exactly (its tangent vectors are
    linear in time), so only acceleration within the window biases the fit.
    """

    def __init__(self, max_extrapolation_s: float = 0.1, window_us: int = 0, max_poses: int = 16, smooth_pose: bool = True):
        self.max_extrapolation_s = float(max_extrapolation_s)
        """Do not extrapolate further than this past the last accepted pose (a long gap makes velocity stale), seconds."""
        self.window_us = int(window_us)
        """Poses accepted within this long before the newest one enter the fit (0 = last two poses only), microseconds."""
        self.max_poses = max(int(max_poses), 2)
        """At most this many poses are kept, poses."""
        self.smooth_pose = bool(smooth_pose)
        """Extrapolate from the fitted line at the newest time instead of the newest pose itself."""
        self._hist: list[tuple[int, np.ndarray]] = []

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        self._hist = [(int(t_us), np.array(T_world_cam, dtype=np.float64))]

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        hist = self._hist + [(int(t_us), np.array(T_world_cam, dtype=np.float64))]
        if self.window_us <= 0:
            self._hist = hist[-2:]
            return
        t_new = hist[-1][0]
        self._hist = [h for h in hist if t_new - h[0] <= self.window_us][-self.max_poses:]
        if len(self._hist) < 2:
            self._hist = hist[-2:]  # a long gap: still keep a pair to take a velocity from

    def _fit(self) -> tuple[np.ndarray, np.ndarray]:
        """(a, b): tangent offset at the newest pose and twist per second of the fitted constant-velocity line."""
        if len(self._hist) < 2:
            return np.zeros(6), np.zeros(6)
        t1, T1 = self._hist[-1]
        if len(self._hist) == 2 or self.window_us <= 0:
            t0, T0 = self._hist[-2]
            if t1 <= t0:
                return np.zeros(6), np.zeros(6)
            return np.zeros(6), gtsam.Pose3.Logmap(gtsam.Pose3(T0).between(gtsam.Pose3(T1))) / ((t1 - t0) * 1e-6)
        ref = gtsam.Pose3(T1)
        ts = np.array([(t - t1) * 1e-6 for t, _ in self._hist])
        xs = np.array([gtsam.Pose3.Logmap(ref.between(gtsam.Pose3(T))) for _, T in self._hist])
        tm = ts.mean()
        var = float(((ts - tm) ** 2).sum())
        if var <= 0.0:
            return np.zeros(6), np.zeros(6)
        b = ((ts - tm)[:, None] * (xs - xs.mean(0))).sum(0) / var
        a = xs.mean(0) - b * tm
        return (a if self.smooth_pose else np.zeros(6)), b

    def twist(self) -> np.ndarray:
        """Body-frame twist (rotation, translation) per second of the fit; zeros with fewer than two poses."""
        return self._fit()[1]

    def predict(self, t_us: int) -> np.ndarray:
        if not self._hist:
            raise RuntimeError("predictor used before reset()")
        t1, T1 = self._hist[-1]
        dt = min(max((int(t_us) - t1) * 1e-6, 0.0), self.max_extrapolation_s)
        if len(self._hist) < 2:
            return T1.copy()
        a, b = self._fit()
        if dt == 0.0 and not np.any(a):
            return T1.copy()
        return gtsam.Pose3(T1).compose(gtsam.Pose3.Expmap(a + b * dt)).matrix()

    def snapshot(self) -> dict:
        return {"hist": [(t, np.copy(T)) for t, T in self._hist]}

    def restore(self, state: dict) -> None:
        self._hist = [(t, np.copy(T)) for t, T in state["hist"]]
