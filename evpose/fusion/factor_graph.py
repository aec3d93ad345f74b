"""Factor-graph fusion of registrations with IMU preintegration (EV-Pose MHFO, later stage).

States ``X(i)`` (IMU-body Pose3), ``V(i)`` (world velocity) and ``B(i)``
(ConstantBias) at every registration time. Factors: ``CombinedImuFactor``
between consecutive states (bias random walk included), the registration as a
robust pose prior with its covariance, a weak constant-velocity prior
(``BetweenFactorVector`` on ``V``), and priors on the first state.

* Inter-TS fusion: one iSAM2 update per registration gives the estimate at once.
* Joint optimisation: a fixed-lag iSAM2 smoother keeps the newest N states
  (smoother "time" = state index, lag N-1) and marginalises the older ones;
  every K updates the window is re-optimised with extra relinearising iSAM2
  iterations. It is :class:`CopyableFixedLagSmoother`, gtsam's
  ``IncrementalFixedLagSmoother`` algorithm (bit-identical estimates when never re-based) on a
  copyable ``ISAM2``, so ``snapshot``/``restore`` cost the same at any step
  (one iSAM2 copy of the window) instead of replaying every input. Every
  :attr:`FactorGraphFusion.rebase_every_states` states it re-bases (rebuilds
  iSAM2 from its serialisable content), so a snapshot stored on disk restores
  at a bounded cost too.

A failed registration (``None``) adds a state constrained only by the IMU and
constant-velocity factors: the pose is IMU-propagated, marked degraded, and its
covariance grows honestly. The first successful registration after a loss
enters with a plain Gaussian (not robust) noise model and triggers a joint
optimisation, so a large correction is accepted at once (re-acquisition). That
optimisation, and one after any update that corrects the new state's velocity
by more than ``relinearize_correction_velocity`` (a start without velocity),
relinearises the window at once instead of waiting for ``relinearize_skip``.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import Trajectory
from evpose.fusion.config import FusionConfig, RegistrationErrorModel, RobustLoss
from evpose.fusion.fixed_lag import CopyableFixedLagSmoother
from evpose.fusion.preintegration import ImuBuffer, make_preintegration_params, preintegrate
from evpose.fusion.propagation import NavPropagator, imu_rate_trajectory
from evpose.fusion.registration_offset import OffsetChain, split_ridge
from evpose.fusion.startup import gyro_bias_release_due, gyro_bias_release_params, initial_gyro_bias_sigma, startup_inflated
from evpose.fusion.state import Extrinsic, FusedState
from evpose.fusion.revision_readout import readout_pose


def initial_bias_covariance(config: FusionConfig, R_world_imu: np.ndarray) -> np.ndarray | None:
    """(6, 6) covariance of the initial (accelerometer, gyroscope) bias prior in the IMU frame, or None when it is the
    diagonal of ``init_sigma_acc_bias`` / :func:`initial_gyro_bias_sigma` (``init_sigma_acc_bias_vertical`` off)."""
    sv = float(config.init_sigma_acc_bias_vertical)
    if not sv > 0:
        return None
    sh = float(config.init_sigma_acc_bias)
    g = np.asarray(R_world_imu, np.float64)[2, :]  # world z in the IMU frame
    P = np.zeros((6, 6))
    P[:3, :3] = sh**2 * np.eye(3) + (sv**2 - sh**2) * np.outer(g, g)
    P[3:, 3:] = initial_gyro_bias_sigma(config) ** 2 * np.eye(3)
    return P


def initial_bias_noise(gtsam, config: FusionConfig, R_world_imu: np.ndarray):
    """gtsam noise model of :func:`initial_bias_covariance`."""
    P = initial_bias_covariance(config, R_world_imu)
    if P is None:
        return gtsam.noiseModel.Diagonal.Sigmas(np.array([config.init_sigma_acc_bias] * 3 + [initial_gyro_bias_sigma(config)] * 3))
    return gtsam.noiseModel.Gaussian.Covariance(P)


def registration_covariance(config: FusionConfig, covariance_6x6: np.ndarray | None, scale: float | None = None) -> np.ndarray:
    """Registration covariance (rotation, translation; camera frame), scaled, with defaults and a floor.

    A missing, non-finite or non-positive-definite covariance (a degenerate
    registration Hessian) falls back to the configured default sigmas.
    """
    floor = _covariance_floor(config.registration_min_sigma)
    if covariance_6x6 is not None:
        c = np.empty((6, 6))
        # ``0.5 * (c + c.T)`` and its finiteness in one compiled pass (the same operations, fewer numpy calls).
        if _symmetrised(np.asarray(covariance_6x6, dtype=np.float64).reshape(6, 6), c) and _positive_definite(c):
            # correlated errors: see the config field; ``c * scale + floor``, element by element as numpy does it
            return _scaled_plus(c, float(config.registration_covariance_scale if scale is None else scale), floor)
    # built only when used (every update pays for this function)
    sr, st = config.registration_default_sigma_rot, config.registration_default_sigma_trans
    return np.diag([sr * sr] * 3 + [st * st] * 3) + floor


@nb.njit(cache=True)
def _symmetrised(c, out):
    """``out = 0.5 * (c + c.T)`` (6, 6); whether every element is finite."""
    finite = True
    for i in range(6):
        for j in range(6):
            v = 0.5 * (c[i, j] + c[j, i])
            out[i, j] = v
            if not np.isfinite(v):
                finite = False
    return finite


@nb.njit(cache=True)
def _scaled_plus(c, scale, floor):
    """``c * scale + floor`` (6, 6) as a new array."""
    out = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            out[i, j] = c[i, j] * scale + floor[i, j]
    return out


def _positive_definite(c: np.ndarray) -> bool:
    """Whether the Cholesky factorisation of the finite symmetric ``c`` succeeds (cheaper than an eigen-decomposition):
    the LAPACK gufunc behind ``np.linalg.cholesky`` called directly, which reports a failure as an all-NaN factor
    instead of an exception (~4 of the ~9 us ``np.linalg.cholesky`` costs per update)."""
    with np.errstate(invalid="ignore"):  # the gufunc flags a failed factorisation as an invalid operation
        factor = _cholesky_lo(c, signature="d->d")
    return not np.isnan(factor[0, 0])


try:
    from numpy.linalg._umath_linalg import cholesky_lo as _cholesky_lo
except ImportError:  # another numpy layout: the public function, its exception turned into the same NaN factor
    def _cholesky_lo(c, signature=None):
        try:
            return np.linalg.cholesky(c)
        except np.linalg.LinAlgError:
            return np.full(np.shape(c), np.nan)


_FLOORS: dict[float, np.ndarray] = {}


def _covariance_floor(sigma: float) -> np.ndarray:
    """``np.eye(6) * sigma**2``, built once per value (the config may change between updates; a few us per update)."""
    floor = _FLOORS.get(sigma)
    if floor is None:
        if len(_FLOORS) > 16:
            _FLOORS.clear()
        floor = _FLOORS[sigma] = np.eye(6) * sigma**2
        floor.setflags(write=False)
    return floor


def usable_pose(T: np.ndarray | None) -> np.ndarray | None:
    """The measured pose as a 4x4 array, or None if missing or not finite (treated as a failed registration)."""
    if T is None:
        return None
    T = np.asarray(T, dtype=np.float64).reshape(4, 4)
    return T if np.isfinite(T).all() else None


_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)
"""The constant-velocity factor's measured velocity change (gtsam copies it into the factor)."""

_X, _V, _B = (ord(c) << 56 for c in "xvb")
"""gtsam ``Symbol`` keys of index 0 of the pose, velocity and bias states (tests check them against gtsam's)."""

_ESTIMATORS: dict = {}


def robust_noise(config: FusionConfig, cov: np.ndarray, robust: bool = True):
    import gtsam

    base = gtsam.noiseModel.Gaussian.Covariance(cov)
    if not robust or config.registration_loss is RobustLoss.NONE:
        return base
    k = config.registration_loss_scale
    # An m-estimator is an immutable parameter object: one per (loss, scale) serves every factor.
    key = (config.registration_loss, float(k))
    est = _ESTIMATORS.get(key)
    if est is None:
        if config.registration_loss is RobustLoss.HUBER:
            est = gtsam.noiseModel.mEstimator.Huber.Create(k)
        else:
            est = gtsam.noiseModel.mEstimator.Cauchy.Create(k)
        _ESTIMATORS[key] = est
    return gtsam.noiseModel.Robust.Create(est, base)


class FactorGraphFusion:
    """iSAM2 / fixed-lag-smoother fusion of registration poses with the IMU."""

    rebase_every_states = 50
    """The smoother rebuilds itself from its factors and linearisation point every this many states (at least the
    window, so that a long window's batch rebuild stays a bounded cost per update; 0: never), so a restored smoother
    replays at most this many updates (:meth:`CopyableFixedLagSmoother.rebase`; a class attribute, not a config
    field: part of the algorithm, fixed by the code the viewer's disk cache is keyed on). Measured against never:
    ``full`` on the 2 s landings (seeds 0-3) 9.152 / 9.510 mm vs 9.151 / 9.510 (346x260 / 240x180), the demo
    15.979 mm either way, its ``--smoothed`` (400-state window, re-based every 400) 12.557 vs 12.504 mm; the seeds'
    smoothed 4.494 / 7.153 vs 4.510 / 7.153 mm; ~0.5 ms per re-base. The viewer's exact seek at 9.5 s in the
    prepared 10 s landing: 0.24-0.27 s instead of 1.55-1.65 s (its disk restore 13 ms instead of 1.2 s)."""

    def __init__(self, config: FusionConfig | None = None, calibration: CameraCalibration | None = None):
        import gtsam

        self.config = config or FusionConfig()
        self.config.validate()
        T_cam_imu = np.eye(4) if calibration is None else calibration.T_cam_imu
        self.time_offset_us = 0 if calibration is None else int(calibration.time_offset_us)
        self.extrinsic = Extrinsic(T_cam_imu)
        self.params = make_preintegration_params(self.config)
        self.buffer = ImuBuffer(self.time_offset_us)
        self._gtsam = gtsam
        self._cv_noise = None
        """(sigma, noise model) of the last constant-velocity factor (see :meth:`_velocity_noise`)."""
        self._reset()

    # ------------------------------------------------------------------ state
    def _reset(self) -> None:
        self.smoother = None
        self.index = -1
        self.n_updates = 0
        self.propagator = NavPropagator(self.buffer, self.params, self.extrinsic)
        self.history: list[tuple] = []
        self.readout_written: dict[int, tuple] = {}  # revision_readout.written_poses' scratch (NavState id -> (it, pose))
        self.degraded = False
        self.last_state: FusedState | None = None
        self.last_registration: tuple[int, np.ndarray] | None = None
        """(state index, measured IMU pose 4x4) of the newest state's registration (None: it had none), for the
        AR(1) registration error models."""
        self.temporary_factor: int | None = None
        """Smoother index of the newest state's extra prior of ``AR1_WHITENED``, removed by the next registration."""
        self.start_us: int | None = None
        """Time of the state ``initialize`` set (``FusionConfig.registration_startup_s`` counts from it)."""
        self.hold_start_us: int | None = None
        """Start time of a running gyroscope-bias hold (``FusionConfig.gyro_bias_hold_s``); None: none or released."""
        self.offset = OffsetChain()
        """The registration offsets' chain (``FusionConfig.registration_offset_tau_s``)."""

    @property
    def initialized(self) -> bool:
        return self.index >= 0

    def _keys(self, i: int):
        # gtsam's ``symbol_shorthand.X(i)`` etc. (``Symbol``: the character in the top byte, the index below), without
        # three pybind calls per use.
        return _X | i, _V | i, _B | i

    def _new_smoother(self):
        gtsam = self._gtsam
        p = gtsam.ISAM2Params()
        p.setRelinearizeThreshold(self.config.relinearize_threshold)
        p.relinearizeSkip = int(self.config.relinearize_skip)
        # Cholesky reports an indeterminate system on the bias keys (information spans ~1e12 between the
        # bias random walk over a few ms and the pose priors); QR factorises the same graph robustly.
        p.setFactorization("QR")
        # Not set (session 42, lat42: recorded inputs of ``full`` 346x260 seed 0 replayed through two fusions stepped
        # alternately, ``/tmp/s42/lat42/fuspair.py``, two runs): enablePartialRelinearizationCheck -0.020 / -0.011 ms per
        # update (mean, of 0.55-0.84), findUnusedFactorSlots -0.005 / -0.014, both -0.015 / -0.022 (+- 0.005-0.010): no
        # gain worth changing the outputs (open loop they move the poses by up to 3e-5 / 2e-11 mm).
        # Smoother "time" is the state index, so the lag is exactly N-1 states.
        n = self.config.window_states
        every = max(int(self.rebase_every_states), n) if self.rebase_every_states else None
        return CopyableFixedLagSmoother(float(n - 1), p, rebase_every=every, newest_last=bool(self.config.newest_state_last))

    # ------------------------------------------------------------ public API
    def initialize(self, t_us: int, T_world_cam: np.ndarray, velocity_world=None, acc_bias=None, gyro_bias=None) -> FusedState:
        """Start the graph at a known camera pose (and optional velocity / biases)."""
        gtsam = self._gtsam
        z = np.zeros(3)
        v = z if velocity_world is None else np.asarray(velocity_world, np.float64).reshape(3)
        ba = z if acc_bias is None else np.asarray(acc_bias, np.float64).reshape(3)
        bg = z if gyro_bias is None else np.asarray(gyro_bias, np.float64).reshape(3)
        T_wc = np.asarray(T_world_cam, np.float64).reshape(4, 4)
        self._reset()
        c = self.config
        T_wi = self.extrinsic.imu_pose(T_wc)
        _, gyro_m = self.buffer.measurement_at(t_us)
        v_imu = self.extrinsic.imu_velocity(T_wi[:3, :3], v, gyro_m - bg)
        pose = gtsam.Pose3(T_wi)
        bias = gtsam.imuBias.ConstantBias(ba, bg)
        x, vk, b = self._keys(0)
        graph = gtsam.NonlinearFactorGraph()
        graph.add(gtsam.PriorFactorPose3(x, pose, gtsam.noiseModel.Diagonal.Sigmas(np.array([c.init_sigma_rot] * 3 + [c.init_sigma_trans] * 3))))
        sigma_v = c.init_sigma_velocity if velocity_world is not None else c.unknown_velocity_sigma
        graph.add(gtsam.PriorFactorVector(vk, v_imu, gtsam.noiseModel.Isotropic.Sigma(3, sigma_v)))
        graph.add(gtsam.PriorFactorConstantBias(b, bias, initial_bias_noise(gtsam, c, T_wi[:3, :3])))
        values = gtsam.Values()
        values.insert(x, pose)
        values.insert(vk, v_imu)
        values.insert(b, bias)
        self.smoother = self._new_smoother()
        self.smoother.update(graph, values, {x: 0.0, vk: 0.0, b: 0.0})
        self.index = 0
        self.t_state_us = int(t_us)
        self.hold_start_us = int(t_us) if c.gyro_bias_hold_s > 0 else None
        self.start_us = int(t_us)
        return self._finish_state(int(t_us), degraded=False)

    def add_imu(self, imu: ImuSamples) -> None:
        """Buffer IMU samples (IMU clock; the calibration's time offset is applied)."""
        self.buffer.add(imu)

    def update(self, t_us: int, T_world_cam_measured: np.ndarray | None, covariance_6x6: np.ndarray | None = None) -> FusedState:
        """Fuse one registration (``None`` = registration failed: propagate and mark degraded)."""
        if not self.initialized:
            raise RuntimeError("FactorGraphFusion.update called before initialize")
        t_us = int(t_us)
        if t_us <= self.t_state_us:
            raise ValueError(f"update time {t_us} us is not after the last state at {self.t_state_us} us")
        return self._add_state(t_us, usable_pose(T_world_cam_measured), covariance_6x6)

    def predict(self, t_us: int) -> FusedState:
        """IMU propagation from the latest state to ``t_us`` without adding a factor."""
        if not self.initialized:
            raise RuntimeError("FactorGraphFusion.predict called before initialize")
        return self.propagator.predict(int(t_us), degraded=self.degraded)

    def predict_view(self, t_us: int) -> FusedState:
        """:meth:`predict` without the copy (the propagator's cached state: read it, never modify it)."""
        if not self.initialized:
            raise RuntimeError("FactorGraphFusion.predict_view called before initialize")
        return self.propagator.predict_view(int(t_us), degraded=self.degraded)

    def imu_rate_poses(self, t0_us: int, t1_us: int) -> Trajectory:
        """Camera poses at IMU sample times in ``[t0, t1)``, each propagated from the state before it."""
        return imu_rate_trajectory(self.history, self.buffer, self.params, self.extrinsic, int(t0_us), int(t1_us))

    def window_poses(self) -> tuple[np.ndarray, np.ndarray]:
        """``(t_us (N,), T_world_cam (N, 4, 4))`` of the states in the window, oldest first: the smoother's current
        (smoothed) estimates, which for older states include the registrations that came after them."""
        n = min(self.config.window_states, len(self.history), self.index + 1)
        t = np.array([h[0] for h in self.history[len(self.history) - n :]], np.int64)
        poses = [self.extrinsic.cam_pose(self.smoother.calculateEstimatePose3(self._keys(self.index - n + 1 + i)[0]).matrix())
                 for i in range(n)]
        return t, np.array(poses).reshape(n, 4, 4)

    def snapshot(self) -> dict:
        """The whole state, independent of this object: a copy of the smoother (its iSAM2 Bayes tree, values and
        factors over the window) plus the bookkeeping. Costs the same at any step (the window is bounded)."""
        p = self.propagator
        # gtsam NavState / ConstantBias are immutable value types, safe to share; the smoother is copied.
        return {"smoother": None if self.smoother is None else self.smoother.copy(), "index": self.index,
                "t_state_us": getattr(self, "t_state_us", None), "n_updates": self.n_updates, "degraded": self.degraded,
                "anchor": (p.t_us, p.nav, p.bias), "history": list(self.history),
                "last_state": None if self.last_state is None else self.last_state.copy(), "imu": self.buffer.samples,
                "last_registration": self.last_registration, "temporary_factor": self.temporary_factor,
                "hold_start_us": self.hold_start_us, "start_us": self.start_us,
                "offset_last": self.offset.last}

    def restore(self, snap: dict) -> None:
        """Put back a snapshot; the snapshot stays usable (its smoother is copied again), and the restored fusion fed
        the same inputs reproduces the uninterrupted run bit for bit."""
        self.buffer = ImuBuffer(self.time_offset_us)
        self.buffer.set_samples(snap["imu"])
        self._reset()
        self.smoother = None if snap["smoother"] is None else snap["smoother"].copy()
        self.index = int(snap["index"])
        if snap["t_state_us"] is not None:
            self.t_state_us = int(snap["t_state_us"])
        self.n_updates = int(snap["n_updates"])
        self.degraded = bool(snap["degraded"])
        t, nav, bias = snap["anchor"]
        if t is not None:
            self.propagator.anchor(t, nav, bias)
        self.history = list(snap["history"])
        self.last_state = None if snap["last_state"] is None else snap["last_state"].copy()
        self.last_registration = snap.get("last_registration")
        self.temporary_factor = snap.get("temporary_factor")
        self.hold_start_us = snap.get("hold_start_us")
        self.start_us = snap.get("start_us")
        self.offset = OffsetChain(snap.get("offset_last"))

    # -------------------------------------------------------------- internals
    def _add_state(self, t_us: int, T_meas_cam: np.ndarray | None, cov_cam: np.ndarray | None) -> FusedState:
        gtsam = self._gtsam
        c = self.config
        i, j = self.index, self.index + 1
        xi, vi, bi = self._keys(i)
        xj, vj, bj = self._keys(j)
        pim = self.propagator.preintegration_to(t_us)
        nav_pred = self.propagator.predict_nav(t_us)  # pim.predict from the anchor (t_us > anchor), usually cached
        dt = (t_us - self.t_state_us) * 1e-6
        if gyro_bias_release_due(c, self.hold_start_us, t_us):
            # The same integral with the held bias's release as this step's random walk (FusionConfig.gyro_bias_hold_s).
            pim = preintegrate(self.buffer, gyro_bias_release_params(c, dt), self.propagator.bias, self.propagator.t_us, t_us)
            self.hold_start_us = None

        graph = gtsam.NonlinearFactorGraph()
        graph.add(gtsam.CombinedImuFactor(xi, vi, xj, vj, bi, bj, pim))
        degraded = T_meas_cam is None
        reacquire = self.degraded and not degraded
        remove, temporary = None, None
        values = gtsam.Values()
        stamp = float(j)
        stamps = {xj: stamp, vj: stamp, bj: stamp}
        if not degraded:
            T_meas_imu = self.extrinsic.imu_pose(T_meas_cam)
            if c.registration_offset_tau_s > 0:
                remove, temporary = self._add_offset_registration(graph, values, stamps, j, t_us, dt, T_meas_imu, cov_cam,
                                                                  nav_pred, robust=not reacquire)
            else:
                cov_cam = startup_inflated(c, self.start_us, t_us, cov_cam)
                remove, temporary = self._add_registration(graph, i, xi, xj, T_meas_imu, cov_cam, robust=not reacquire)
            self.last_registration = (j, T_meas_imu)
        else:
            self.last_registration = None
        graph.add(gtsam.BetweenFactorVector(vi, vj, _ZERO3, self._velocity_noise(c.constant_velocity_sigma * math.sqrt(dt))))
        # Named value arguments select gtsam's insert overload at once: by position pybind11 tries its 45 overloads
        # in order, and the bias is the 44th (~25-40 us per update, the same stored value either way).
        values.insert(xj, pose3=nav_pred.pose())
        values.insert(vj, np.asarray(nav_pred.velocity(), np.float64))
        values.insert(bj, constant_bias=self.propagator.bias)
        if temporary is None and not remove:  # the white model: the call gtsam's own smoother takes too (tests swap it in)
            self.smoother.update(graph, values, stamps)
            self.temporary_factor = None
        else:
            self.temporary_factor = None if temporary is None else int(self.smoother.update(graph, values, stamps, remove)[temporary])
        self.index = j
        self.t_state_us = t_us
        self.n_updates += 1
        velocity = None
        if reacquire or self.n_updates % c.reoptimize_every == 0:
            self._joint_optimisation(force=reacquire and c.relinearize_correction_velocity > 0)
        elif c.relinearize_correction_velocity > 0:
            # A large correction of the new state (a start without velocity) must not stay linearised at the
            # prediction until the state is marginalised: see FusionConfig.relinearize_correction_velocity.
            v = np.asarray(self.smoother.calculateEstimateVector(vj), np.float64)
            d = v - np.asarray(nav_pred.velocity(), np.float64)
            if math.sqrt(d.dot(d)) > c.relinearize_correction_velocity:  # np.linalg.norm's own recipe, without its wrapper
                self._joint_optimisation(force=True)
            else:
                velocity = v  # nothing changed the smoother since: the new state's estimate, read once
        self.degraded = degraded
        return self._finish_state(t_us, degraded=degraded, velocity=velocity)

    def _add_registration(self, graph, i: int, xi, xj, T_meas_imu: np.ndarray, cov_cam, robust: bool):
        """Add the registration's factors on state j = i + 1 to ``graph`` (see ``FusionConfig.registration_error_model``).

        Returns ``(smoother factor indices to remove, position in graph of a factor to remove at the next
        registration)``, either None."""
        gtsam = self._gtsam
        c = self.config
        model = c.registration_error_model
        if model is not RegistrationErrorModel.WHITE:
            model = RegistrationErrorModel(model)  # a config loaded from text holds the string
        prev = self.last_registration
        z = gtsam.Pose3(mat=T_meas_imu)  # by name: the matrix overload at once (as ``values.insert`` below)
        rho = float(c.registration_ar_rho)
        if model is RegistrationErrorModel.WHITE or prev is None or prev[0] != i or rho == 0.0:
            cov = self.extrinsic.imu_covariance(registration_covariance(c, cov_cam))
            graph.add(gtsam.PriorFactorPose3(xj, z, robust_noise(c, cov, robust=robust)))
            return None, None
        q = self.extrinsic.imu_covariance(registration_covariance(c, cov_cam, c.registration_ar_covariance_scale))
        # Log((z_i^-1 z_j)^-1 x_i^-1 x_j) ~ e_j - e_i: the relative registration's residual.
        between = robust_noise(c, q * (c.registration_ar_between_scale / rho), robust=robust)
        graph.add(gtsam.BetweenFactorPose3(xi, xj, gtsam.Pose3(prev[1]).between(z), between))
        graph.add(gtsam.PriorFactorPose3(xj, z, robust_noise(c, q / (1.0 - rho) ** 2, robust=robust)))
        if model is RegistrationErrorModel.AR1_BETWEEN:
            return None, None
        remove = None if self.temporary_factor is None else [self.temporary_factor]
        graph.add(gtsam.PriorFactorPose3(xj, z, robust_noise(c, q / (rho * (1.0 - rho)), robust=robust)))
        return remove, graph.size() - 1

    def _add_offset_registration(self, graph, values, stamps, j: int, t_us: int, dt: float, T_meas_imu: np.ndarray, cov_cam,
                                 nav_pred, robust: bool):
        """Add state j's registration through its offset (``FusionConfig.registration_offset_tau_s``,
        :mod:`evpose.fusion.registration_offset`); returns ``(smoother factor indices to remove, position in graph of
        a factor to remove at the next registration)`` as :meth:`_add_registration`."""
        c = self.config
        base = registration_covariance(c, cov_cam)
        widened = startup_inflated(c, self.start_us, t_us, cov_cam)
        cov = base if widened is cov_cam else registration_covariance(c, widened)
        white, slow = split_ridge(float(c.registration_offset_ratio), cov, base)
        noise = robust_noise(c, self.extrinsic.imu_covariance(white), robust=robust)
        temporary, chained = self.offset.add(self._gtsam, c, self.smoother, graph, values, stamps, j, t_us, dt,
                                             self._gtsam.Pose3(T_meas_imu), noise, slow, self.extrinsic,
                                             nav_pred.pose().matrix())
        # The previous offset's extra prior goes when the chain carries on from it (a restarted chain leaves it: its
        # offset may have left the window; a state without registration forgets it, so it then stays, a little weight
        # more on that one offset).
        remove = [self.temporary_factor] if chained and self.temporary_factor is not None else None
        return remove, temporary

    def _velocity_noise(self, sigma: float):
        """The constant-velocity factor's isotropic noise model; the step (so sigma) rarely changes between updates,
        and a gtsam noise model is immutable, so the last one is reused."""
        last = self._cv_noise
        if last is None or last[0] != sigma:
            last = self._cv_noise = (sigma, self._gtsam.noiseModel.Isotropic.Sigma(3, sigma))
        return last[1]

    def _joint_optimisation(self, force: bool = False) -> None:
        """Re-optimise the whole window: extra relinearising iSAM2 iterations with no new factors (``force``: the
        first relinearises whatever ``relinearize_skip`` says)."""
        for k in range(self.config.reoptimize_iterations):
            if force and k == 0:
                self.smoother.update(force_relinearize=True)
            else:
                self.smoother.update()

    def _finish_state(self, t_us: int, degraded: bool, velocity: np.ndarray | None = None) -> FusedState:
        """``velocity``: the newest velocity's estimate when already read since the smoother's last update."""
        x, v, b = self._keys(self.index)
        pose = self.smoother.calculateEstimatePose3(x)
        vel = np.asarray(self.smoother.calculateEstimateVector(v), np.float64) if velocity is None else velocity
        bias = self.smoother.calculateEstimateConstantBias(b)
        nav = self._gtsam.NavState(pose, vel)
        self.propagator.anchor(t_us, nav, bias)
        self.history.append((t_us, nav, bias))
        del self.history[: -(self.config.window_states + 2)]  # keeps the newest window_states + 2
        cov = np.asarray(self.smoother.marginalCovariance(x)) if self.config.compute_covariance else None
        previous, self.last_state = self.last_state, self.propagator.fused_state(t_us, nav, bias, cov, degraded)
        if self.config.revision_readout_states > 0:
            self.last_state.readout_T_world_cam = readout_pose(self, self.last_state.T_world_cam, previous)
        return self.last_state
