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

import enum
from dataclasses import dataclass, field

import gtsam
import numba as nb
import numpy as np


class VelocityFrame(str, enum.Enum):
    """The frame in which the filter holds the linear velocity constant between registrations."""

    WORLD = "world"
    """Constant body angular rate and constant world-frame velocity: a camera that turns while it flies straight
    (a drone yawing on its way down) keeps its velocity, so the model needs no acceleration to follow it."""
    BODY = "body"
    """Constant body-frame twist (a screw motion): turning also turns the velocity, so a camera that yaws at
    ``w`` while flying straight at ``v`` looks to the model like a sideways acceleration of ``w v``
    (1-1.5 m/s^2 on the simulated landing) that the filter follows with a lag."""


@dataclass
class MotionFilterConfig:
    """Constant-velocity Kalman filter settings (``stpe`` mode with ``motion_model: kalman``)."""

    angular_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "rad/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white angular acceleration driving the twist, rad/s^2/sqrt(Hz).

    On the simulated landing (built map, 2 s, gate 4) 0.5 / 1 / 2 / 8 for both noises gave ATE
    56 / 63 / 67 / 278 mm at 346x260 and 74 / 140 / 149 / 1265 mm at 240x180: a stiff model
    rides out the biased registrations better than a loose one follows them. Session 9 (seeds 0-3, 13.42 / 19.00 mm
    with 0.5 / 0.5): angular 0.25 / 0.1 gave 20.16 / 29.99, 72.09 / 419.2 mm; linear 0.25 28.26 mm at 240x180
    (17.77 at 346x260); angular 0.25 with linear 1.0 30.86 / 68.49 mm. Not the model's lag either: the filter's
    twist moved by the true acceleration before every update (an oracle) gave 12.90 / 24.10 mm."""
    linear_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "m/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white linear acceleration, m/s^2/sqrt(Hz)."""
    measurement_covariance_scale: float = field(default=1.0, metadata={"min": 0.01, "max": 1000.0, "step": 0.1, "unit": "ratio"})
    """Factor on the registration covariance; > 1 when neighbouring map points' errors are correlated (they are:
    points of one edge see the same events), ratio."""
    measurement_anisotropy: float = field(default=0.2, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "exponent"})
    """Exponent ``g`` that widens the registration covariance along its weak directions before it is fused
    (:func:`stretch_weak_directions`; 0 = the covariance as reported), exponent.

    The reported covariance assumes independent point errors, but the registration's errors are biases shared
    by whole edges (trail, map), and along the tilt-vs-sideways valley they move the pose far more than the
    covariance says: the filter should lean on its motion model there more than elsewhere. In the covariance's
    correlation form (scale-free), eigenvalue ``l`` becomes ``l (l / l_min)^g``. ``stpe``, 2 s landing from
    ground truth, built map, mean ATE of seeds 0-3 at 346x260 / 240x180: 0 / 0.2 / 0.3 / 0.5 gave 15.48 /
    21.53, 14.68 / 21.41, 14.39 / 21.24, 16.02 / 22.66 mm (``prior_residual_sigma`` 0.2); with 0.25, 0 / 0.3
    gave 15.82 / 23.80, 14.86 / 21.60 mm. Scaling the rotation by the altitude instead of the correlation
    form: 0.2 / 0.3 / 0.4 / 0.6 gave 15.43 / 21.30, 15.26 / 20.78, 15.38 / 21.13, 17.38 / 23.25 mm (with
    ``crowded_radius_px`` scaled to 2.08 px at 240x180). A uniform ``measurement_covariance_scale`` of 0.5 / 2 /
    4 gave 16.09 / 23.08, 15.91 / 21.79, 15.37 / 21.89 mm (same crowding). Diagonal covariances are unchanged.
    With ``map_refinement.register_after_updates`` 10: 0 / 0.2 / 0.3 gave 13.60 / 20.06, 13.42 / 19.00, 13.49 /
    18.46 mm, but the bundled demo's camera accelerates at 4-5 m/s^2, which a model leaned on lags: ``stpe`` on
    ``demo_data/landing.h5`` (``--align none``, lost from ~2 s in every case) 126.4 / 140.1 / 161.2 mm ATE RMSE
    (134.9 mm before this session's changes), so 0.2. ``full`` does not use this filter."""
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
    prior_in_registration: bool = True
    """Give the registration the prediction as a prior with the filter's predicted covariance.

    (The fused covariance is then the events' alone, but the prior still shapes the
    registration's minimum, so the prediction counts a little twice.) The prior is
    anisotropic: it holds the registration where the events say little (the
    tilt-vs-sideways valley over flat ground) and lets it follow them elsewhere, so
    fewer registrations slide off and get gated. On the simulated landing (2 s, from
    ground truth, ``prior_residual_sigma`` 0.25), mean over five starts (``warmup_ms``
    20-40), this prior with a world-frame velocity against neither (session 2's filter):
    ATE 50.9 / 73.5 mm, ARE 0.77 / 1.14 deg, 2-4 / 21-24 not-OK updates at 346x260
    and 60.6 / 97.2 mm, 0.87 / 1.08 deg, 1-2 / 9-12 at 240x180 (map built at the start
    of session 3); 55.1 / 65.8 mm and 53.9 / 57.6 mm on session 3's builder; on the
    simulator's true edges 17.9 / 18.5 mm and 26 / 28 mm (one start). With a
    body-frame velocity the prior gave 116 / 116 mm (``prior_residual_sigma`` 0.5):
    it needs the world-frame prediction. Taking the prior back out of the registered
    pose before fusing it (no double counting, linearised) gave 68 / 53 / 58 / 54 mm
    on those four cases against 52 / 57 / 46 / 44 mm: on a biased map the second
    count of the prediction is a useful regulariser. On the bundled 4 s demo, whose
    camera accelerates at 4-5 m/s^2, the stiffer model costs accuracy before the track
    is lost at 0.22 s (as before): 71 / 60 mm over 0-0.5 / 0.5-1 s against 61 / 48 mm
    (63 / 47 mm without the double count)."""
    prior_residual_sigma: float = field(default=0.2, metadata={"min": 0.05, "max": 2.0, "step": 0.05, "unit": "TDF"})
    """Typical TDF residual of one point that converts the filter's prior into the registration cost's units
    (``prior_in_registration``; larger = a stiffer prior), TDF units.

    Session 7 (2 s landing, seeds 0-3, mean ATE 346x260 / 240x180, ``crowded_radius_px`` 2.08 px at 240x180,
    no ``measurement_anisotropy``): 0.15 / 0.2 / 0.25 / 0.3 gave 15.92 / 22.06, 15.48 / 21.53, 15.82 / 22.21,
    16.31 / 23.04 mm; with ``measurement_anisotropy`` 0.3 and the default crowding, 0.2 / 0.25 gave 14.39 / 21.24
    and 14.86 / 21.60 mm. Earlier sessions:

    On the simulated landing (``registration.min_inlier_ratio`` 0.05; pinned built map,
    346x260 / 240x180) 0.25 / 0.35 / 0.5 / 0.7 gave 52 / 46 / 57 / 70 mm and
    77 / 82 / 78 / 88 mm ATE; today's built map 32 / 42 / 52 / - and 44 / 44 / 57 / - mm;
    the true edges - / 17 / 14.5 / 20 mm and - / 23 / 23 / 36 mm; the demo's first
    second 81-63 / 96-77 / 128-117 / - mm (0-0.5 s, 0.5-1 s). A stiffer prior suits
    an accurate map and a smooth flight, a weaker one a biased map and a
    manoeuvring camera; run-to-run changes of 10-15 mm come from single slides
    along the tilt-vs-shift valley, so only the trend is meaningful."""
    velocity_frame: VelocityFrame = VelocityFrame.WORLD
    """Frame of the constant linear velocity: world (straight flight while turning) or body (screw motion).

    Alone it changes little on the simulated landing (70.7 / 84.0 mm against 71.2 / 82.3 mm
    at 346x260 / 240x180), but the filter's prior in the registration (``prior_in_registration``)
    only helps with it."""
    weak_gate_sigma: float = field(default=3.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """A weak registration (inlier share between ``registration.weak_inlier_ratio`` and ``min_inlier_ratio``) is
    fused only if its innovation is within this Mahalanobis distance of the prediction; otherwise the track is
    lost, sigma. 2 / 3 / 4 gave the same demo track (the registration's prior keeps its innovations small)."""
    max_gated: int = field(default=20, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """After this many registrations in a row were gated out the next one is fused anyway (the model may be
    the one that is wrong), updates."""
    adaptive_noise_max_scale: float = field(default=1.0, metadata={"min": 1.0, "max": 100.0, "step": 0.5, "unit": "ratio"})
    """Largest factor the innovation test may put on both acceleration noises (1 = a fixed motion model), ratio.

    The filter is stiff so that it rides out biased registrations in steady flight, which makes it lag
    a manoeuvre: the innovations then keep pointing the same way. Their whitened running mean against
    their running power (``|mean|^2 / mean |z|^2``: ~``1 / adaptive_noise_window`` for white
    innovations, 1 for a constant bias) measures that consistency; above ``adaptive_noise_threshold``
    the noises are scaled up linearly to this factor at full consistency (at once), and they fall back
    with the window's time constant once the innovations turn white again. The ratio is scale-free on
    purpose: with the filter's prior in the registration (``prior_in_registration``) the registration is
    pulled toward the prediction, so the innovations are small (0.3-0.6 sigma) even while the track
    drifts, and a plain normalised-innovation test (NIS against its chi-square bound) never fires.

    Off by default, measured (``stpe``, all else default): on the bundled demo (4 s, 4-5 m/s^2)
    10 / 0.15 (max scale / threshold) and 4 / 0.3 cut the error before the first loss from 71 / 61 mm
    to 40 / 35 and 55 / 44 mm (0-0.5 / 0.5-1 s), but the loss at 0.22 s stays (the registration's
    inlier-ratio test fails there and on a quarter of the updates even at the true pose: too few
    events) and the looser filter then re-acquires into wrong minima, reporting poses 0.35-0.55 m off
    at 1-2 s (and, with 10, metres off after 2 s) where the fixed model stays lost. On the simulated
    landing (five starts, 346x260 / 240x180) 50.9 / 60.6 mm became 75.4 / 71.2 and 64.6 / 57.4 mm:
    the map's biased registrations also give consistent innovations, which the test cannot tell from
    a lag."""
    adaptive_noise_window: float = field(default=20.0, metadata={"min": 2.0, "max": 1000.0, "step": 1.0, "unit": "updates"})
    """Time constant of the running innovation mean and power (``adaptive_noise_max_scale``), updates."""
    adaptive_noise_threshold: float = field(default=0.3, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Innovation consistency (``|mean|^2 / power``) below which the motion model is left as configured, ratio."""


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
    """``(I - K H) P (I - K H)^T + K R K^T`` with ``H = [I6 0]``, symmetrised: the Joseph form keeps P symmetric
    positive definite in float64. Compiled: the numpy version is five 12x12 calls."""
    A = np.eye(12)
    for i in range(12):
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
    d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    scale = np.outer(d, d)
    lam, V = np.linalg.eigh(cov / scale)
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
        self._P = np.zeros((12, 12))
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
        return np.linalg.inv(P[:6, :6])

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
            P = _propagate_world(self._P, np.ascontiguousarray(step.T), np.ascontiguousarray(T_pred[:3, :3].T), float(dt),
                                 float(c.angular_acceleration_noise) ** 2 * g, float(c.linear_acceleration_noise) ** 2 * g)
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
        self._t = int(t_us)
        self._T, self._P = T_pred, P
        self._motion_cache = None
        self.last_fused = False
        if covariance is None or not np.all(np.isfinite(covariance)):
            return T_pred.copy()
        R = 0.5 * (covariance + covariance.T) * float(self.config.measurement_covariance_scale)
        if float(self.config.measurement_anisotropy) > 0:
            R = stretch_weak_directions(R, float(self.config.measurement_anisotropy))
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
        self._xi = self._xi + dx[6:]
        self._P = _joseph_update(P, np.ascontiguousarray(K), np.ascontiguousarray(R))
        return self._T.copy()

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
                "innovation": self.last_innovation_sigma, "fused": self.last_fused, "rejected": self._rejected,
                "innovation_mean": np.copy(self._innovation_mean), "innovation_power": self._innovation_power,
                "noise_scale": self.noise_scale}

    def restore(self, state: dict) -> None:
        self._t = state["t"]
        self._T = None if state["T"] is None else np.copy(state["T"])
        self._xi = np.copy(state["xi"])
        self._P = np.copy(state["P"])
        self.last_innovation_sigma = state["innovation"]
        self.last_fused = state["fused"]
        self._rejected = state["rejected"]
        # Snapshots taken before the adaptation existed restore to "no adaptation yet".
        self._innovation_mean = np.array(state.get("innovation_mean", np.zeros(6)), dtype=np.float64)
        self._innovation_power = float(state.get("innovation_power", 0.0))
        self.noise_scale = float(state.get("noise_scale", 1.0))
        self._motion_cache = None
