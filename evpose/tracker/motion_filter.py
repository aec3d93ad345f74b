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
motion model. State: pose ``T_world_cam``, body-frame angular rate ``omega`` and a
linear velocity ``v`` (in the world frame by default, see :class:`VelocityFrame`);
error state ``(d_pose, d_omega, d_v)`` with the pose perturbed on the right,
``T = T_hat Exp(d_pose)``. Process model: constant rates driven by white angular /
linear acceleration.
"""

from __future__ import annotations

import gtsam
import numba as nb
import numpy as np

from evpose.core.lapack_calls import eigh as _eigh, inv as _inv, solve as _solve
# The settings live in their own module; re-exported here, where they were (imports and docs name them here).
from evpose.tracker.motion_filter_config import MotionFilterConfig, VelocityFrame  # noqa: F401


@nb.njit(cache=True)
def _propagate_world(P, Rs_t, Rt, dt, qa, ql):
    """``F P F^T + Q`` of the world-velocity model over ``dt`` (see :meth:`ConstantVelocityKalman._propagate`), symmetrised;
    ``qa`` / ``ql`` are the squared angular / linear acceleration noises. One compiled call instead of a dozen small
    numpy ones (59 -> 25 us per update with the machine loaded)."""
    F = np.eye(12)
    for i in range(3):
        F[i, 6 + i] = dt
        for j in range(3):
            F[i, j] = Rs_t[i, j]
            F[3 + i, 3 + j] = Rs_t[i, j]
            F[3 + i, 9 + j] = Rt[i, j] * dt
    FP = np.zeros((12, 12))
    for i in range(12):
        for k in range(12):
            f = F[i, k]
            if f != 0.0:
                for j in range(12):
                    FP[i, j] += f * P[k, j]
    out = np.zeros((12, 12))
    for i in range(12):
        for j in range(12):
            acc = 0.0
            for k in range(12):
                acc += FP[i, k] * F[j, k]
            out[i, j] = acc
    # White acceleration on the twist; the linear one acts on the world velocity while the position error lives in the
    # body frame, hence R'^T in the position-velocity block.
    for i in range(3):
        out[i, i] += qa * dt**3 / 3.0
        out[i, 6 + i] += qa * dt**2 / 2.0
        out[6 + i, i] += qa * dt**2 / 2.0
        out[6 + i, 6 + i] += qa * dt
        out[3 + i, 3 + i] += ql * dt**3 / 3.0
        out[9 + i, 9 + i] += ql * dt
        for j in range(3):
            out[3 + i, 9 + j] += Rt[i, j] * ql * dt**2 / 2.0
            out[9 + j, 3 + i] += Rt[i, j] * ql * dt**2 / 2.0
    _symmetrise(out)
    return out


@nb.njit(cache=True)
def _propagate_world_accel(P, Rs_t, Rt, dt, qa, ql, qj):
    """:func:`_propagate_world` with a world-frame linear acceleration in the state (error state of 15: rotation,
    position, angular rate, velocity, acceleration; ``linear_jerk_noise``): ``d_p' = R_step^T d_p + dt R'^T d_v +
    dt^2/2 R'^T d_a``, ``d_v' = d_v + dt d_a``; ``qj`` is the squared jerk noise on the acceleration, ``ql`` still
    drives the velocity directly."""
    F = np.eye(15)
    for i in range(3):
        F[i, 6 + i] = dt
        F[9 + i, 12 + i] = dt
        for j in range(3):
            F[i, j] = Rs_t[i, j]
            F[3 + i, 3 + j] = Rs_t[i, j]
            F[3 + i, 9 + j] = Rt[i, j] * dt
            F[3 + i, 12 + j] = Rt[i, j] * 0.5 * dt * dt
    out = F @ P @ F.T
    for i in range(3):
        out[i, i] += qa * dt**3 / 3.0
        out[i, 6 + i] += qa * dt**2 / 2.0
        out[6 + i, i] += qa * dt**2 / 2.0
        out[6 + i, 6 + i] += qa * dt
        # White acceleration on the velocity plus white jerk on the acceleration (the constant-acceleration model's
        # position / velocity / acceleration block), the position rows in the body frame.
        out[3 + i, 3 + i] += ql * dt**3 / 3.0 + qj * dt**5 / 20.0
        out[9 + i, 9 + i] += ql * dt + qj * dt**3 / 3.0
        out[9 + i, 12 + i] += qj * dt**2 / 2.0
        out[12 + i, 9 + i] += qj * dt**2 / 2.0
        out[12 + i, 12 + i] += qj * dt
        for j in range(3):
            c = Rt[i, j] * (ql * dt**2 / 2.0 + qj * dt**4 / 8.0)
            out[3 + i, 9 + j] += c
            out[9 + j, 3 + i] += c
            c = Rt[i, j] * qj * dt**3 / 6.0
            out[3 + i, 12 + j] += c
            out[12 + j, 3 + i] += c
    _symmetrise(out)
    return out


@nb.njit(cache=True)
def _symmetrise(out):
    """Replace both off-diagonal halves of the square ``out`` by their mean, in place (rounding keeps P symmetric)."""
    n = out.shape[0]
    for i in range(n):
        for j in range(i):
            a = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = a
            out[j, i] = a


@nb.njit(cache=True)
def _joseph_update(P, K, R):
    """``(I - K H) P (I - K H)^T + K R K^T`` with ``H = [I6 0]`` (P 12x12 or 15x15), symmetrised: the Joseph form keeps P symmetric
    positive definite in float64. Compiled: the numpy version is five 12x12 calls."""
    n = P.shape[0]
    A = np.eye(n)
    for i in range(n):
        for j in range(6):
            A[i, j] -= K[i, j]
    AP = A @ P
    KR = K @ R
    out = AP @ A.T + KR @ K.T
    _symmetrise(out)
    return out


def stretch_weak_directions(cov: np.ndarray, exponent: float) -> np.ndarray:
    """``cov`` (symmetric positive definite) with each eigenvalue ``l`` of its correlation form (unit diagonal, so
    rotation and translation units do not matter) raised to ``l (l / l_min)^exponent``: the best determined
    combination keeps its variance, weaker ones grow the more, the weaker they are (see
    ``MotionFilterConfig.measurement_anisotropy``). A diagonal covariance comes back unchanged."""
    d = np.sqrt(np.maximum(cov.diagonal(), 1e-300))
    scale = d[:, None] * d[None, :]  # np.outer's own expression, without its wrapper
    lam, V = _eigh(cov / scale)
    lam = np.maximum(lam, 1e-12)
    out = (V * (lam * (lam / lam[0]) ** float(exponent))) @ V.T * scale
    return 0.5 * (out + out.T)



class ConstantVelocityKalman:
    """SE(3) pose + twist Kalman filter fed with registrations; a :class:`~evpose.tracker.predictor.MotionPredictor`."""

    def __init__(self, config: MotionFilterConfig | None = None, max_extrapolation_s: float = 0.1):
        self.config = config or MotionFilterConfig()
        self.max_extrapolation_s = float(max_extrapolation_s)
        """Do not extrapolate further than this past the last fused pose, seconds."""
        self._t: int | None = None
        self._T: np.ndarray | None = None
        self._xi = np.zeros(6)
        """Angular rate (body, rad/s) then linear velocity (m/s, in ``config.velocity_frame``)."""
        self._acc = np.zeros(3)
        """World-frame linear acceleration, m/s^2 (stays zero unless ``linear_jerk_noise`` is on)."""
        self._P = np.zeros((self._n, self._n))
        self.last_innovation_sigma = 0.0
        """Mahalanobis distance of the last registration from the prediction, sigma."""
        self.last_fused = False
        """Whether the last :meth:`correct` fused its registration (False: no covariance, or gated out)."""
        self._rejected = 0
        self._motion_cache = None
        self._q_cache = None
        self._innovation_mean = np.zeros(6)
        """Running mean of the whitened innovations (``adaptive_noise_max_scale``)."""
        self._innovation_power = 0.0
        """Running mean of their squared norm."""
        self.noise_scale = 1.0
        """Factor currently on both acceleration noises (1 unless the innovations keep pointing one way)."""

    # ------------------------------------------------------------ protocol
    @property
    def _with_acceleration(self) -> bool:
        """The constant-acceleration model (``linear_jerk_noise`` > 0, world-frame velocity only)."""
        return float(self.config.linear_jerk_noise) > 0 and self._world_velocity

    @property
    def _n(self) -> int:
        """Size of the error state."""
        return 15 if self._with_acceleration else 12

    def _initial_covariance(self) -> np.ndarray:
        c = self.config
        sd = [np.radians(c.initial_rotation_std_deg)] * 3 + [c.initial_translation_std_m] * 3
        sd += [c.initial_angular_rate_std] * 3 + [c.initial_velocity_std] * 3
        if self._with_acceleration:
            sd += [c.initial_acceleration_std] * 3
        return np.diag(np.square(np.maximum(sd, 1e-9)))

    def reset(self, t_us: int, T_world_cam: np.ndarray) -> None:
        """Start at a known pose with zero twist (``update`` with a second pose sets the twist)."""
        self._t = int(t_us)
        self._T = np.array(T_world_cam, dtype=np.float64)
        self._xi = np.zeros(6)
        self._acc = np.zeros(3)
        self._P = self._initial_covariance()
        self._motion_cache = None
        self._reset_adaptation()

    def _reset_adaptation(self) -> None:
        self._innovation_mean = np.zeros(6)
        self._innovation_power = 0.0
        self.noise_scale = 1.0

    def update(self, t_us: int, T_world_cam: np.ndarray) -> None:
        """Set the pose to a known one at ``t_us``; the twist becomes the motion since the previous pose (seeding)."""
        if self._T is None:
            self.reset(t_us, T_world_cam)
            return
        T = np.array(T_world_cam, dtype=np.float64)
        dt = (int(t_us) - self._t) * 1e-6
        if dt > 0:
            self._xi = gtsam.Pose3.Logmap(gtsam.Pose3(self._T).between(gtsam.Pose3(T))) / dt
            if self._world_velocity:
                self._xi[3:] = (T[:3, 3] - self._T[:3, 3]) / dt
        self._acc = np.zeros(3)
        self._t = int(t_us)
        self._T = T
        self._P = self._initial_covariance()
        self._motion_cache = None

    @property
    def _world_velocity(self) -> bool:
        return VelocityFrame(self.config.velocity_frame) is VelocityFrame.WORLD

    def twist(self) -> np.ndarray:
        """Body-frame twist (rotation, translation) per second (the world velocity turned into the camera frame)."""
        if self._world_velocity and self._T is not None:
            return np.concatenate([self._xi[:3], self._T[:3, :3].T @ self._xi[3:]])
        return self._xi.copy()

    def prior_information(self, t_us: int) -> np.ndarray:
        """(6, 6) inverse covariance of the predicted pose at ``t_us`` (for the registration's prior)."""
        _, P = self._propagate(t_us)
        return _inv(P[:6, :6])

    def covariance(self) -> np.ndarray:
        """(6, 6) covariance of the pose (body frame, rotation then translation)."""
        return self._P[:6, :6].copy()

    def predict(self, t_us: int) -> np.ndarray:
        if self._T is None:
            raise RuntimeError("predictor used before reset()")
        return self._motion(t_us)[0].copy()

    def _motion(self, t_us: int) -> tuple[np.ndarray, gtsam.Pose3 | np.ndarray | None]:
        """(predicted pose, motion step or None for no motion) at ``t_us``; remembered until the state changes,
        because the tracker asks for the prediction and then corrects at the same time. With a world-frame
        velocity the step is the body rotation alone, a (3, 3) matrix."""
        key = (int(t_us), self._t)
        if self._motion_cache is not None and self._motion_cache[0] == key:
            return self._motion_cache[1], self._motion_cache[2]
        dt = self._dt(t_us)
        if dt == 0.0:
            out = (self._T.copy(), None)
        elif self._world_velocity:
            step = gtsam.Rot3.Expmap(self._xi[:3] * dt).matrix()
            T = np.eye(4)
            T[:3, :3] = self._T[:3, :3] @ step
            T[:3, 3] = self._T[:3, 3] + self._xi[3:] * dt
            if self._with_acceleration:
                T[:3, 3] += self._acc * (0.5 * dt * dt)
            out = (T, step)
        else:
            step = gtsam.Pose3.Expmap(self._xi * dt)
            out = (gtsam.Pose3(self._T).compose(step).matrix(), step)
        self._motion_cache = (key, out[0], out[1])
        return out

    # ---------------------------------------------------------------- filter
    def _dt(self, t_us: int) -> float:
        return min(max((int(t_us) - self._t) * 1e-6, 0.0), self.max_extrapolation_s)

    def _propagate(self, t_us: int) -> tuple[np.ndarray, np.ndarray]:
        """(predicted pose, predicted covariance) at ``t_us``; the covariance is remembered with the motion
        (the tracker asks for the prior information and then corrects at the same time)."""
        dt = self._dt(t_us)
        T_pred, step = self._motion(t_us)
        if step is None:
            return T_pred.copy(), self._P.copy()
        cache = self._motion_cache
        if len(cache) > 3:
            return T_pred.copy(), cache[3].copy()
        if self._world_velocity:
            # R = R^ Exp(d_rot), p = p^ + R^ d_p (right perturbation, first order), v = v^ + d_v in the world:
            # d_rot' = R_step^T d_rot + dt d_omega, d_p' = R_step^T d_p + dt R'^T d_v.
            c = self.config
            g = self.noise_scale**2
            args = (self._P, np.ascontiguousarray(step.T), np.ascontiguousarray(T_pred[:3, :3].T), float(dt),
                    float(c.angular_acceleration_noise) ** 2 * g, float(c.linear_acceleration_noise) ** 2 * g)
            P = (_propagate_world_accel(*args, float(c.linear_jerk_noise) ** 2 * g) if self._with_acceleration
                 else _propagate_world(*args))
        else:
            F = np.eye(12)
            F[:6, :6] = step.inverse().AdjointMap()
            F[:6, 6:] = np.eye(6) * dt
            P = F @ self._P @ F.T + self._process_noise(dt)
            P = 0.5 * (P + P.T)
        self._motion_cache = cache + (P,)
        return T_pred.copy(), P.copy()

    def _process_noise(self, dt: float) -> np.ndarray:
        """(12, 12) white-acceleration process noise over ``dt`` seconds (cached: the update interval rarely changes)."""
        c = self.config
        key = (dt, float(c.angular_acceleration_noise), float(c.linear_acceleration_noise), self.noise_scale)
        if self._q_cache is None or self._q_cache[0] != key:
            q = np.array([c.angular_acceleration_noise] * 3 + [c.linear_acceleration_noise] * 3, dtype=np.float64) ** 2
            q = q * self.noise_scale**2
            Q = np.zeros((12, 12))
            Q[:6, :6] = np.diag(q * dt**3 / 3.0)
            Q[:6, 6:] = Q[6:, :6] = np.diag(q * dt**2 / 2.0)
            Q[6:, 6:] = np.diag(q * dt)
            self._q_cache = (key, Q)
        return self._q_cache[1]

    def coast(self, t_us: int) -> np.ndarray:
        """No measurement at ``t_us``: move the state forward on the motion model; returns the pose."""
        T_pred, P = self._propagate(t_us)
        self._advance_velocity(t_us)
        self._t, self._T, self._P = int(t_us), T_pred, P
        self._motion_cache = None
        return T_pred.copy()

    def correct(self, t_us: int, T_measured: np.ndarray, covariance: np.ndarray | None, gate_sigma: float | None = None) -> np.ndarray:
        """Fuse a registration at ``t_us`` (pose and (6, 6) body-frame covariance); returns the filtered pose.

        Without a covariance (or when the innovation fails the gate) the filter coasts. ``gate_sigma``, if given,
        is a strict gate for this registration instead of ``config.gate_sigma``: it is never overridden by
        ``max_gated`` and does not count towards it (a weak registration must agree with the motion model).
        """
        if self._T is None:
            raise RuntimeError("predictor used before reset()")
        T_pred, P = self._propagate(t_us)
        self._advance_velocity(t_us)
        self._t = int(t_us)
        self._T, self._P = T_pred, P
        self._motion_cache = None
        self.last_fused = False
        if covariance is None or not np.isfinite(covariance).all() or not np.all(covariance.diagonal() > 0):
            # A covariance without a positive variance on every axis is no usable measurement (and its correlation
            # form would overflow: seen on a lost 3 s landing with ``linear_acceleration_noise`` 2).
            return T_pred.copy()
        R = 0.5 * (covariance + covariance.T) * float(self.config.measurement_covariance_scale)
        if float(self.config.measurement_anisotropy) > 0:
            R = stretch_weak_directions(R, float(self.config.measurement_anisotropy))
        y = gtsam.Pose3.Logmap(gtsam.Pose3(T_pred).between(gtsam.Pose3(np.asarray(T_measured, dtype=np.float64))))
        S = P[:6, :6] + R
        try:
            sol = _solve(S, np.concatenate((y[:, None], P[:6, :]), axis=1))  # np.column_stack's result
        except np.linalg.LinAlgError:
            return T_pred.copy()
        S_inv_y = sol[:, 0]
        K = sol[:, 1:].T  # (n, 6) = P H^T S^-1, S symmetric
        d2 = float(y @ S_inv_y)
        self.last_innovation_sigma = float(np.sqrt(max(d2, 0.0)))
        self._adapt(y, S)
        if gate_sigma is not None:
            if self.last_innovation_sigma > float(gate_sigma):
                return T_pred.copy()
        else:
            gate = float(self.config.gate_sigma)
            if gate > 0 and self.last_innovation_sigma > gate and self._rejected < int(self.config.max_gated):
                self._rejected += 1
                return T_pred.copy()
            self._rejected = 0
        self.last_fused = True
        dx = K @ y
        self._T = gtsam.Pose3(T_pred).compose(gtsam.Pose3.Expmap(dx[:6])).matrix()
        self._xi = self._xi + dx[6:12]
        if self._with_acceleration:
            self._acc = self._acc + dx[12:]
        self._P = _joseph_update(P, np.ascontiguousarray(K), np.ascontiguousarray(R))
        return self._T.copy()

    def _advance_velocity(self, t_us: int) -> None:
        """The constant-acceleration model's velocity moves on with its acceleration to ``t_us`` (before ``_t`` does)."""
        if self._with_acceleration:
            self._xi[3:] = self._xi[3:] + self._acc * self._dt(t_us)

    def _adapt(self, y: np.ndarray, S: np.ndarray) -> None:
        """Update the innovation statistics with ``y`` (covariance ``S``) and set the noise scale for the next
        propagation (see ``adaptive_noise_max_scale``); gated-out innovations count too: a model that lags
        produces them."""
        c = self.config
        top = float(c.adaptive_noise_max_scale)
        if top <= 1.0:
            return
        try:
            z = np.linalg.solve(np.linalg.cholesky(S), y)
        except np.linalg.LinAlgError:
            return
        b = 1.0 / max(float(c.adaptive_noise_window), 1.0)
        self._innovation_mean = (1.0 - b) * self._innovation_mean + b * z
        self._innovation_power = (1.0 - b) * self._innovation_power + b * float(z @ z)
        if self._innovation_power <= 0.0:
            return
        r = float(self._innovation_mean @ self._innovation_mean) / self._innovation_power
        r0 = min(max(float(c.adaptive_noise_threshold), 0.0), 0.999)
        target = 1.0 + (top - 1.0) * min(max((r - r0) / (1.0 - r0), 0.0), 1.0)
        # Up at once, down with the window's time constant: falling back the moment the filter has caught up
        # would let the lag build again (a limit cycle between stiff and loose).
        self.noise_scale = target if target >= self.noise_scale else target + (self.noise_scale - target) * (1.0 - b)

    def snapshot(self) -> dict:
        return {"t": self._t, "T": None if self._T is None else np.copy(self._T), "xi": np.copy(self._xi), "P": np.copy(self._P),
                "acc": np.copy(self._acc),
                "innovation": self.last_innovation_sigma, "fused": self.last_fused, "rejected": self._rejected,
                "innovation_mean": np.copy(self._innovation_mean), "innovation_power": self._innovation_power,
                "noise_scale": self.noise_scale}

    def restore(self, state: dict) -> None:
        self._t = state["t"]
        self._T = None if state["T"] is None else np.copy(state["T"])
        self._xi = np.copy(state["xi"])
        self._acc = np.array(state.get("acc", np.zeros(3)), dtype=np.float64)
        self._P = np.copy(state["P"])
        self.last_innovation_sigma = state["innovation"]
        self.last_fused = state["fused"]
        self._rejected = state["rejected"]
        # Snapshots taken before the adaptation existed restore to "no adaptation yet".
        self._innovation_mean = np.array(state.get("innovation_mean", np.zeros(6)), dtype=np.float64)
        self._innovation_power = float(state.get("innovation_power", 0.0))
        self.noise_scale = float(state.get("noise_scale", 1.0))
        self._motion_cache = None
