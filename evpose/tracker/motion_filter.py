"""Constant-velocity Kalman filter on SE(3): the ``stpe`` mode's motion model when registrations are fused, not copied.

One registration of a 5 ms field is weakly constrained along some directions:
while the camera moves along one image axis only the edges across that axis
fire, and a tilt then looks almost like a sideways shift (on the simulated
landing the registration slides 2-3 deg / 25 cm along that valley in the first
80 ms, from the true pose, on a perfect map). Copying each registration into the
track lets every such slide through, and a velocity taken from the last two
poses turns the per-update noise into ~3 m/s of velocity error. A pose prior
inside the registration does not help either: when the pose follows the
prediction, the velocity taken from the poses equals the predicted one, so a
velocity error never decays.

This filter treats each registration as a measurement with its covariance
(the registration's ``(J^T W J)^-1 sigma^2``, scaled): along well constrained
directions it follows the registration, along the valley it follows the
motion model. State: pose ``T_world_cam`` and body-frame twist ``xi`` (rotation,
translation per second, gtsam order); error state ``(d_pose, d_xi)`` with the
pose perturbed on the right, ``T = T_hat Exp(d_pose)``. Process model: constant
twist driven by white angular / linear acceleration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gtsam
import numpy as np


@dataclass
class MotionFilterConfig:
    """Constant-velocity Kalman filter settings (``stpe`` mode with ``motion_model: kalman``)."""

    angular_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "rad/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white angular acceleration driving the twist, rad/s^2/sqrt(Hz).

    On the simulated landing (built map, 2 s, gate 4) 0.5 / 1 / 2 / 8 for both noises gave ATE
    56 / 63 / 67 / 278 mm at 346x260 and 74 / 140 / 149 / 1265 mm at 240x180: a stiff model
    rides out the biased registrations better than a loose one follows them."""
    linear_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "m/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white linear acceleration, m/s^2/sqrt(Hz)."""
    measurement_covariance_scale: float = field(default=1.0, metadata={"min": 0.01, "max": 1000.0, "step": 0.1, "unit": "ratio"})
    """Factor on the registration covariance; > 1 when neighbouring map points' errors are correlated (they are:
    points of one edge see the same events), ratio."""
    initial_rotation_std_deg: float = field(default=0.1, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "deg"})
    """Uncertainty of the initial orientation, degrees."""
    initial_translation_std_m: float = field(default=0.005, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "m"})
    """Uncertainty of the initial position, metres."""
    initial_angular_rate_std: float = field(default=0.2, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "rad/s"})
    """Uncertainty of the initial angular rate, rad/s."""
    initial_velocity_std: float = field(default=0.2, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "m/s"})
    """Uncertainty of the initial velocity, m/s."""
    gate_sigma: float = field(default=4.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """Registrations whose innovation exceeds this Mahalanobis distance are not fused (0 = fuse all), sigma.

    Without a gate the filter follows the registration's slide along the tilt-vs-shift
    valley in the first 80 ms of the simulated landing (only edges across the motion
    fire; the registration lands 2-3 deg off, from the true pose, even on a perfect
    map, with a covariance that claims 0.2 deg): 489 mm ATE on the perfect map; with
    4 sigma, 21 mm. 3 / 4 / 6 sigma: 62 / 63 / 323 mm at 346x260 (acceleration noise 1-2)."""
    prior_in_registration: bool = False
    """Give the registration the prediction as a prior with the filter's predicted covariance.

    (The fused covariance is then the events' alone, but the prior still shapes the
    registration's minimum, so the prediction counts a little twice.) With
    ``registration.prior_residual_sigma`` 0.5 and acceleration noise 1 it gave
    62 / 96 mm ATE at 346x260 / 240x180 against 63 / 140 mm without; not the default
    because at acceleration noise 0.5 the plain filter is as good (56 / 74 mm)."""
    max_gated: int = field(default=20, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """After this many registrations in a row were gated out the next one is fused anyway (the model may be
    the one that is wrong), updates."""


class ConstantVelocityKalman:
    """SE(3) pose + twist Kalman filter fed with registrations; a :class:`~evpose.tracker.predictor.MotionPredictor`."""

    def __init__(self, config: MotionFilterConfig | None = None, max_extrapolation_s: float = 0.1):
        self.config = config or MotionFilterConfig()
        self.max_extrapolation_s = float(max_extrapolation_s)
        """Do not extrapolate further than this past the last fused pose, seconds."""
        self._t: int | None = None
        self._T: np.ndarray | None = None
        self._xi = np.zeros(6)
        self._P = np.zeros((12, 12))
        self.last_innovation_sigma = 0.0
        """Mahalanobis distance of the last registration from the prediction, sigma."""
        self.last_fused = False
        """Whether the last :meth:`correct` fused its registration (False: no covariance, or gated out)."""
        self._rejected = 0
        self._motion_cache = None
        self._q_cache = None

    # ------------------------------------------------------------ protocol
    def _initial_covariance(self) -> np.ndarray:
        c = self.config
        sd = [np.radians(c.initial_rotation_std_deg)] * 3 + [c.initial_translation_std_m] * 3
        sd += [c.initial_angular_rate_std] * 3 + [c.initial_velocity_std] * 3
        return np.diag(np.square(np.maximum(sd, 1e-9)))

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        """Start at a known pose with zero twist (``update`` with a second pose sets the twist)."""
        self._t = int(t_us)
        self._T = np.array(T_world_cam, dtype=np.float64)
        self._xi = np.zeros(6)
        self._P = self._initial_covariance()
        self._motion_cache = None

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        """Set the pose to a known one at ``t_us``; the twist becomes the motion since the previous pose (seeding)."""
        if self._T is None:
            self.reset(t_us, T_world_cam)
            return
        T = np.array(T_world_cam, dtype=np.float64)
        dt = (int(t_us) - self._t) * 1e-6
        if dt > 0:
            self._xi = gtsam.Pose3.Logmap(gtsam.Pose3(self._T).between(gtsam.Pose3(T))) / dt
        self._t = int(t_us)
        self._T = T
        self._P = self._initial_covariance()
        self._motion_cache = None

    def twist(self) -> np.ndarray:
        """Body-frame twist (rotation, translation) per second."""
        return self._xi.copy()

    def prior_information(self, t_us: int) -> np.ndarray:
        """(6, 6) inverse covariance of the predicted pose at ``t_us`` (for the registration's prior)."""
        _, P = self._propagate(t_us)
        return np.linalg.inv(P[:6, :6])

    def covariance(self) -> np.ndarray:
        """(6, 6) covariance of the pose (body frame, rotation then translation)."""
        return self._P[:6, :6].copy()

    def predict(self, t_us: int) -> np.ndarray:
        if self._T is None:
            raise RuntimeError("predictor used before reset()")
        return self._motion(t_us)[0].copy()

    def _motion(self, t_us: int) -> tuple[np.ndarray, gtsam.Pose3 | None]:
        """(predicted pose, motion step or None for no motion) at ``t_us``; remembered until the state changes,
        because the tracker asks for the prediction and then corrects at the same time."""
        key = (int(t_us), self._t)
        if self._motion_cache is not None and self._motion_cache[0] == key:
            return self._motion_cache[1], self._motion_cache[2]
        dt = self._dt(t_us)
        if dt == 0.0:
            out = (self._T.copy(), None)
        else:
            step = gtsam.Pose3.Expmap(self._xi * dt)
            out = (gtsam.Pose3(self._T).compose(step).matrix(), step)
        self._motion_cache = (key, out[0], out[1])
        return out

    # ---------------------------------------------------------------- filter
    def _dt(self, t_us: int) -> float:
        return min(max((int(t_us) - self._t) * 1e-6, 0.0), self.max_extrapolation_s)

    def _propagate(self, t_us: int) -> tuple[np.ndarray, np.ndarray]:
        """(predicted pose, predicted covariance) at ``t_us``."""
        dt = self._dt(t_us)
        T_pred, step = self._motion(t_us)
        if step is None:
            return T_pred.copy(), self._P.copy()
        F = np.eye(12)
        F[:6, :6] = step.inverse().AdjointMap()
        F[:6, 6:] = np.eye(6) * dt
        P = F @ self._P @ F.T + self._process_noise(dt)
        return T_pred.copy(), 0.5 * (P + P.T)

    def _process_noise(self, dt: float) -> np.ndarray:
        """(12, 12) white-acceleration process noise over ``dt`` seconds (cached: the update interval rarely changes)."""
        c = self.config
        key = (dt, float(c.angular_acceleration_noise), float(c.linear_acceleration_noise))
        if self._q_cache is None or self._q_cache[0] != key:
            q = np.array([c.angular_acceleration_noise] * 3 + [c.linear_acceleration_noise] * 3, dtype=np.float64) ** 2
            Q = np.zeros((12, 12))
            Q[:6, :6] = np.diag(q * dt**3 / 3.0)
            Q[:6, 6:] = Q[6:, :6] = np.diag(q * dt**2 / 2.0)
            Q[6:, 6:] = np.diag(q * dt)
            self._q_cache = (key, Q)
        return self._q_cache[1]

    def coast(self, t_us: int) -> np.ndarray:
        """No measurement at ``t_us``: move the state forward on the motion model; returns the pose."""
        T_pred, P = self._propagate(t_us)
        self._t, self._T, self._P = int(t_us), T_pred, P
        self._motion_cache = None
        return T_pred.copy()

    def correct(self, t_us: int, T_measured: np.ndarray, covariance: np.ndarray | None) -> np.ndarray:
        """Fuse a registration at ``t_us`` (pose and (6, 6) body-frame covariance); returns the filtered pose.

        Without a covariance (or when the innovation fails the gate) the filter coasts.
        """
        if self._T is None:
            raise RuntimeError("predictor used before reset()")
        T_pred, P = self._propagate(t_us)
        self._t = int(t_us)
        self._T, self._P = T_pred, P
        self._motion_cache = None
        self.last_fused = False
        if covariance is None or not np.all(np.isfinite(covariance)):
            return T_pred.copy()
        R = 0.5 * (covariance + covariance.T) * float(self.config.measurement_covariance_scale)
        y = gtsam.Pose3.Logmap(gtsam.Pose3(T_pred).between(gtsam.Pose3(np.asarray(T_measured, dtype=np.float64))))
        S = P[:6, :6] + R
        try:
            sol = np.linalg.solve(S, np.column_stack([y, P[:6, :]]))
        except np.linalg.LinAlgError:
            return T_pred.copy()
        S_inv_y = sol[:, 0]
        K = sol[:, 1:].T  # (12, 6) = P H^T S^-1, S symmetric
        d2 = float(y @ S_inv_y)
        self.last_innovation_sigma = float(np.sqrt(max(d2, 0.0)))
        gate = float(self.config.gate_sigma)
        if gate > 0 and self.last_innovation_sigma > gate and self._rejected < int(self.config.max_gated):
            self._rejected += 1
            return T_pred.copy()
        self._rejected = 0
        self.last_fused = True
        dx = K @ y
        self._T = gtsam.Pose3(T_pred).compose(gtsam.Pose3.Expmap(dx[:6])).matrix()
        self._xi = self._xi + dx[6:]
        I_KH = np.eye(12)
        I_KH[:, :6] -= K
        # Joseph form keeps P symmetric positive definite in float64.
        P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
        self._P = 0.5 * (P_new + P_new.T)
        return self._T.copy()

    def snapshot(self) -> dict:
        return {"t": self._t, "T": None if self._T is None else self._T.copy(), "xi": self._xi.copy(), "P": self._P.copy(),
                "innovation": self.last_innovation_sigma, "fused": self.last_fused, "rejected": self._rejected}

    def restore(self, state: dict) -> None:
        self._t = state["t"]
        self._T = None if state["T"] is None else state["T"].copy()
        self._xi = state["xi"].copy()
        self._P = state["P"].copy()
        self.last_innovation_sigma = state["innovation"]
        self.last_fused = state["fused"]
        self._rejected = state["rejected"]
        self._motion_cache = None
