"""Constant-velocity Kalman filter: follows a constant twist, weighs noisy registrations, gates far ones, snapshots."""

import gtsam
import numpy as np
import pytest

from evpose.tracker.motion_filter import ConstantVelocityKalman, MotionFilterConfig, VelocityFrame

XI = np.array([0.1, -0.2, 0.05, 1.0, 0.0, -0.5])  # rad/s, m/s
T0 = gtsam.Pose3(gtsam.Rot3.RzRyRx(0.1, 0.2, 0.3), gtsam.Point3(1, 2, 3))
SCREW = MotionFilterConfig(velocity_frame=VelocityFrame.BODY)
"""The tests below that follow :func:`pose` (a constant body twist) use the body-frame model that predicts it exactly."""


def pose(t_s: float) -> np.ndarray:
    return T0.compose(gtsam.Pose3.Expmap(XI * t_s)).matrix()


V_WORLD = np.array([3.0, 0.5, -1.0])  # m/s
W_BODY = np.array([0.3, -0.2, 0.5])  # rad/s


def straight_while_turning(t_s: float) -> np.ndarray:
    """A camera flying straight at ``V_WORLD`` while it turns at ``W_BODY`` (a drone yawing on its way down)."""
    T = np.eye(4)
    T[:3, :3] = T0.rotation().matrix() @ gtsam.Rot3.Expmap(W_BODY * t_s).matrix()
    T[:3, 3] = T0.translation() + V_WORLD * t_s
    return T


def error(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    e = gtsam.Pose3.Logmap(gtsam.Pose3(A).between(gtsam.Pose3(B)))
    return float(np.linalg.norm(e[3:])), float(np.degrees(np.linalg.norm(e[:3])))


def seeded(config: MotionFilterConfig | None = SCREW, motion=pose) -> ConstantVelocityKalman:
    kf = ConstantVelocityKalman(config)
    kf.reset(0, motion(0.0))
    kf.update(5_000, motion(0.005))  # seeds the twist, as TrackingSession does from ground truth
    return kf


def test_world_velocity_model_predicts_straight_flight_while_turning_exactly_and_the_body_model_does_not():
    world = seeded(MotionFilterConfig(velocity_frame=VelocityFrame.WORLD), straight_while_turning)
    body = seeded(SCREW, straight_while_turning)
    assert np.allclose(world.predict(100_000), straight_while_turning(0.1), atol=1e-9)
    assert error(body.predict(100_000), straight_while_turning(0.1))[0] > 0.005  # the screw curves away
    # The twist handed to the lag compensation is body-frame in both models.
    assert np.allclose(world.twist()[3:], straight_while_turning(0.005)[:3, :3].T @ V_WORLD, atol=1e-9)


def test_world_velocity_filter_averages_noisy_registrations_of_straight_flight_while_turning():
    rng = np.random.default_rng(1)
    sd_t, sd_r = 0.01, np.radians(0.2)
    cov = np.diag([sd_r**2] * 3 + [sd_t**2] * 3)
    kf = seeded(MotionFilterConfig(velocity_frame=VelocityFrame.WORLD, angular_acceleration_noise=0.2, linear_acceleration_noise=0.2),
                straight_while_turning)
    raw, filt = [], []
    for k in range(2, 200):
        t = k * 0.005
        noise = np.concatenate([rng.normal(0, sd_r, 3), rng.normal(0, sd_t, 3)])
        meas = (gtsam.Pose3(straight_while_turning(t)) * gtsam.Pose3.Expmap(noise)).matrix()
        out = kf.correct(k * 5_000, meas, cov)
        raw.append(error(meas, straight_while_turning(t))[0])
        filt.append(error(out, straight_while_turning(t))[0])
    assert np.sqrt(np.mean(np.square(filt[20:]))) < 0.5 * np.sqrt(np.mean(np.square(raw[20:])))
    # Its own covariance is consistent with its error (NEES of the position about 3, not orders off).
    P = kf.covariance()
    e = gtsam.Pose3.Logmap(gtsam.Pose3(straight_while_turning(199 * 0.005)).between(gtsam.Pose3(out)))
    assert float(e[3:] @ np.linalg.solve(P[3:, 3:], e[3:])) < 30.0


@pytest.mark.parametrize("frame", list(VelocityFrame))
def test_a_velocity_error_decays_under_exact_registrations(frame):
    motion = straight_while_turning if frame is VelocityFrame.WORLD else pose
    kf = ConstantVelocityKalman(MotionFilterConfig(velocity_frame=frame))
    kf.reset(0, motion(0.0))  # zero twist: the whole velocity is an error to learn
    cov = np.diag([1e-6] * 6)
    for k in range(1, 120):
        out = kf.correct(k * 5_000, motion(k * 0.005), cov)
    assert error(kf.predict(120 * 5_000), motion(0.6))[0] < 0.002
    assert error(out, motion(119 * 0.005))[0] < 1e-3


def test_seeded_filter_predicts_a_constant_twist_exactly():
    kf = seeded()
    assert np.allclose(kf.twist(), XI, atol=1e-9)
    assert np.allclose(kf.predict(20_000), pose(0.020), atol=1e-9)


def test_exact_measurements_of_a_constant_twist_keep_the_filter_on_it():
    kf = seeded()
    cov = np.diag([1e-6] * 3 + [1e-6] * 3)
    for k in range(2, 40):
        T = kf.correct(k * 5_000, pose(k * 0.005), cov)
        assert kf.last_fused
    assert error(T, pose(39 * 0.005))[0] < 1e-6
    assert np.allclose(kf.twist(), XI, atol=1e-4)


def test_filter_averages_noisy_registrations_below_their_noise():
    rng = np.random.default_rng(0)
    sd_t, sd_r = 0.01, np.radians(0.2)
    cov = np.diag([sd_r**2] * 3 + [sd_t**2] * 3)
    kf = seeded(MotionFilterConfig(angular_acceleration_noise=0.2, linear_acceleration_noise=0.2))
    raw, filt = [], []
    for k in range(2, 200):
        t = k * 0.005
        noise = np.concatenate([rng.normal(0, sd_r, 3), rng.normal(0, sd_t, 3)])
        meas = (gtsam.Pose3(pose(t)) * gtsam.Pose3.Expmap(noise)).matrix()
        out = kf.correct(k * 5_000, meas, cov)
        raw.append(error(meas, pose(t))[0])
        filt.append(error(out, pose(t))[0])
    assert np.sqrt(np.mean(np.square(filt[20:]))) < 0.5 * np.sqrt(np.mean(np.square(raw[20:])))


def test_a_registration_far_outside_the_gate_is_not_fused_until_too_many_in_a_row():
    kf = seeded(MotionFilterConfig(gate_sigma=4.0, max_gated=2))
    cov = np.diag([1e-6] * 3 + [1e-6] * 3)
    far = (gtsam.Pose3(pose(0.010)) * gtsam.Pose3.Expmap(np.array([0, 0, 0, 0.5, 0, 0]))).matrix()
    for k, fused in ((2, False), (3, False), (4, True)):
        out = kf.correct(k * 5_000, far, cov)
        assert kf.last_fused is fused
        assert kf.last_innovation_sigma > 4.0
        if not fused:
            assert np.allclose(out, pose(k * 0.005), atol=1e-9)  # coasting on the model


def test_without_a_covariance_the_filter_coasts():
    kf = seeded()
    out = kf.correct(10_000, np.eye(4), None)
    assert not kf.last_fused
    assert np.allclose(out, pose(0.010), atol=1e-9)
    assert np.allclose(kf.coast(15_000), pose(0.015), atol=1e-9)


def test_snapshot_restore_replays_bit_identically():
    cov = np.diag([1e-4] * 3 + [1e-4] * 3)
    kf = seeded()
    kf.correct(10_000, pose(0.0101), cov)
    snap = kf.snapshot()
    a = [kf.correct(k * 5_000, pose(k * 0.0051), cov) for k in range(3, 8)]
    kf.restore(snap)
    b = [kf.correct(k * 5_000, pose(k * 0.0051), cov) for k in range(3, 8)]
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert np.array_equal(kf.covariance(), kf.covariance().T)


def test_prior_information_is_the_inverse_predicted_pose_covariance():
    kf = seeded()
    info = kf.prior_information(10_000)
    assert info.shape == (6, 6)
    assert np.all(np.linalg.eigvalsh(info) > 0)


def test_compiled_world_propagation_equals_the_matrix_formula():
    from evpose.tracker.motion_filter import _propagate_world

    rng = np.random.default_rng(2)
    A = rng.normal(size=(12, 12))
    P = A @ A.T
    Rs = gtsam.Rot3.Expmap(np.array([0.01, -0.02, 0.005])).matrix()
    R1 = gtsam.Rot3.RzRyRx(0.3, -0.2, 1.0).matrix()
    dt, qa, ql = 0.005, 0.25, 0.36
    F = np.eye(12)
    F[:3, :3] = F[3:6, 3:6] = Rs.T
    F[:3, 6:9] = np.eye(3) * dt
    F[3:6, 9:12] = R1.T * dt
    Q = np.zeros((12, 12))
    for blk, q in ((slice(0, 3), qa), (slice(3, 6), ql)):
        Q[blk, blk] = np.eye(3) * q * dt**3 / 3
    Q[0:3, 6:9] = Q[6:9, 0:3] = np.eye(3) * qa * dt**2 / 2
    Q[6:9, 6:9] = np.eye(3) * qa * dt
    Q[9:12, 9:12] = np.eye(3) * ql * dt
    Q[3:6, 9:12] = R1.T * ql * dt**2 / 2  # world-frame acceleration seen from the body-frame position error
    Q[9:12, 3:6] = Q[3:6, 9:12].T
    expected = F @ P @ F.T + Q
    assert np.allclose(_propagate_world(P, np.ascontiguousarray(Rs.T), np.ascontiguousarray(R1.T), dt, qa, ql), expected, atol=1e-12)


ADAPTIVE = dict(velocity_frame=VelocityFrame.WORLD, angular_acceleration_noise=0.2, linear_acceleration_noise=0.2)
ACCEL = np.array([4.0, -2.0, 0.0])  # m/s^2, a manoeuvre the stiff model lags


def accelerating(t_s: float) -> np.ndarray:
    """Straight while turning, then accelerating at ``ACCEL`` from 0.1 s on."""
    T = straight_while_turning(t_s)
    T[:3, 3] += 0.5 * ACCEL * max(t_s - 0.1, 0.0) ** 2
    return T


def run_filter(config: MotionFilterConfig, motion, steps: int, sd_t: float = 0.01, seed: int = 3):
    """Feed noisy registrations of ``motion`` every 5 ms; returns (filter, position errors, noise scales)."""
    rng = np.random.default_rng(seed)
    sd_r = np.radians(0.2)
    cov = np.diag([sd_r**2] * 3 + [sd_t**2] * 3)
    kf = seeded(config, motion)
    errs, scales = [], []
    for k in range(2, steps):
        t = k * 0.005
        noise = np.concatenate([rng.normal(0, sd_r, 3), rng.normal(0, sd_t, 3)])
        meas = gtsam.Pose3(motion(t)).compose(gtsam.Pose3.Expmap(noise)).matrix()
        out = kf.correct(int(round(t * 1e6)), meas, cov)
        errs.append(error(out, motion(t))[0])
        scales.append(kf.noise_scale)
    return kf, np.array(errs), np.array(scales)


def test_adaptive_noise_is_off_by_default_and_then_changes_nothing():
    assert MotionFilterConfig().adaptive_noise_max_scale == 1.0
    a, err_a, scale_a = run_filter(MotionFilterConfig(**ADAPTIVE), accelerating, 120)
    b, err_b, _ = run_filter(MotionFilterConfig(**ADAPTIVE, adaptive_noise_window=5.0, adaptive_noise_threshold=0.0), accelerating, 120)
    assert np.all(scale_a == 1.0)
    assert np.array_equal(err_a, err_b) and np.array_equal(a.snapshot()["P"], b.snapshot()["P"])


def test_consistent_innovations_of_a_manoeuvre_raise_the_noise_and_cut_the_lag():
    fixed = MotionFilterConfig(**ADAPTIVE)
    adaptive = MotionFilterConfig(**ADAPTIVE, adaptive_noise_max_scale=10.0, adaptive_noise_threshold=0.15)
    _, err_fixed, _ = run_filter(fixed, accelerating, 200)
    _, err_adapt, scales = run_filter(adaptive, accelerating, 200)
    late = slice(100, None)  # 0.5-1 s: well into the acceleration
    assert scales[late].max() > 1.5
    assert np.sqrt(np.mean(err_adapt[late] ** 2)) < 0.8 * np.sqrt(np.mean(err_fixed[late] ** 2))


def test_white_innovations_of_a_steady_flight_leave_the_noise_nearly_as_configured():
    adaptive = MotionFilterConfig(**ADAPTIVE, adaptive_noise_max_scale=10.0, adaptive_noise_threshold=0.3)
    _, _, scales = run_filter(adaptive, straight_while_turning, 300)
    assert np.median(scales[40:]) < 1.5


def test_adaptive_state_is_part_of_the_snapshot():
    adaptive = MotionFilterConfig(**ADAPTIVE, adaptive_noise_max_scale=10.0, adaptive_noise_threshold=0.15)
    kf, _, scales = run_filter(adaptive, accelerating, 120)
    assert scales[-1] > 1.0
    state = kf.snapshot()
    cov = np.diag([np.radians(0.2) ** 2] * 3 + [0.01**2] * 3)
    first = [kf.correct(int(k * 5000), accelerating(k * 0.005), cov) for k in range(120, 140)]
    kf.restore(state)
    assert kf.noise_scale == scales[-1]
    again = [kf.correct(int(k * 5000), accelerating(k * 0.005), cov) for k in range(120, 140)]
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    # A snapshot from before the adaptation existed restores to "no adaptation yet".
    old = {k: v for k, v in state.items() if k not in ("innovation_mean", "innovation_power", "noise_scale")}
    kf.restore(old)
    assert kf.noise_scale == 1.0


def test_a_strict_gate_is_never_overridden_and_does_not_count_towards_max_gated():
    kf = seeded(MotionFilterConfig(gate_sigma=4.0, max_gated=1))
    cov = np.diag([1e-6] * 3 + [1e-6] * 3)
    far = (gtsam.Pose3(pose(0.010)) * gtsam.Pose3.Expmap(np.array([0, 0, 0, 0.5, 0, 0]))).matrix()
    for k in (2, 3, 4):
        predicted = kf.predict(k * 5_000)
        out = kf.correct(k * 5_000, far, cov, gate_sigma=3.0)
        assert not kf.last_fused and kf.last_innovation_sigma > 3.0
        assert np.array_equal(out, predicted)  # coasting on the model
    # The strict rejections did not count: the ordinary gate still rejects once before max_gated lets one through.
    kf.correct(25_000, far, cov)
    assert not kf.last_fused
    near = (gtsam.Pose3(pose(0.030)) * gtsam.Pose3.Expmap(np.array([0, 0, 0, 1e-4, 0, 0]))).matrix()
    kf.correct(30_000, near, np.diag([1e-4] * 6), gate_sigma=3.0)
    assert kf.last_fused


def _valley_covariance(z_m: float = 4.0) -> np.ndarray:
    """A registration covariance with the tilt-vs-sideways valley of a downward camera: rotation about y and
    translation along x nearly cancel (t_x ~ -z omega_y), so their combination is far less certain than either
    alone suggests."""
    sd_r, sd_t = np.radians(0.05), 0.002
    cov = np.diag([sd_r**2] * 3 + [sd_t**2] * 3)
    weak = np.zeros(6)
    weak[1], weak[3] = 1.0 / z_m, -1.0  # 1 m of sideways shift with the tilt that hides it at the image centre
    return cov + np.outer(weak, weak) * 0.02**2


def test_stretch_weak_directions_leaves_a_diagonal_covariance_alone():
    from evpose.tracker.motion_filter import stretch_weak_directions

    cov = np.diag([np.radians(0.2) ** 2] * 3 + [0.01**2] * 3)
    assert np.allclose(stretch_weak_directions(cov, 0.3), cov, rtol=1e-12, atol=0)


def test_stretch_weak_directions_widens_the_valley_and_keeps_the_best_determined_direction():
    from evpose.tracker.motion_filter import stretch_weak_directions

    cov = _valley_covariance()
    out = stretch_weak_directions(cov, 0.3)
    d = np.sqrt(np.diag(cov))
    lam, V = np.linalg.eigh(cov / np.outer(d, d))
    lam_out = np.array([V[:, i] @ (out / np.outer(d, d)) @ V[:, i] for i in range(6)])
    assert np.isclose(lam_out[0], lam[0], rtol=1e-9)  # the best determined combination is untouched
    assert np.allclose(lam_out, lam * (lam / lam[0]) ** 0.3, rtol=1e-9)
    assert lam_out[-1] > 2.0 * lam[-1]  # the valley grows
    # Scale-free: rotation in other units (here x 1000) gives the same covariance in those units.
    D = np.diag([1e3] * 3 + [1.0] * 3)
    assert np.allclose(stretch_weak_directions(D @ cov @ D, 0.3), D @ out @ D, rtol=1e-9)


VALLEY_STEP = np.array([0, 1.0 / 4.0, 0, -1.0, 0, 0]) * 0.01
"""1 cm sideways with the tilt that hides it at the image centre from 4 m (the valley of :func:`_valley_covariance`)."""
DEPTH_STEP = np.array([0, 0, 0, 0, 0, 0.01])
"""1 cm along the optical axis (well determined)."""


def _followed(exponent: float, step: np.ndarray) -> float:
    """Share of a registration's offset ``step`` from the prediction that the filtered position takes."""
    kf = seeded(MotionFilterConfig(measurement_anisotropy=exponent))
    predicted = kf.predict(10_000)
    out = kf.correct(10_000, (gtsam.Pose3(predicted) * gtsam.Pose3.Expmap(step)).matrix(), _valley_covariance())
    return float(np.linalg.norm(gtsam.Pose3.Logmap(gtsam.Pose3(predicted).between(gtsam.Pose3(out)))[3:]) / np.linalg.norm(step[3:]))


def test_measurement_anisotropy_makes_the_filter_follow_a_registration_less_along_its_valley():
    valley = _followed(0.3, VALLEY_STEP) / _followed(0.0, VALLEY_STEP)
    depth = _followed(0.3, DEPTH_STEP) / _followed(0.0, DEPTH_STEP)
    assert valley < 0.5 * depth  # the valley loses far more weight than a well determined direction
    assert depth > 0.6


def _cornering(t_s: float) -> np.ndarray:
    """A camera turning a corner: constant world acceleration (5, -5, 0) m/s^2 while it yaws at ``W_BODY``."""
    T = straight_while_turning(t_s)
    T[:3, 3] += 0.5 * np.array([5.0, -5.0, 0.0]) * t_s**2
    return T


def test_acceleration_state_follows_a_cornering_camera_that_the_constant_velocity_model_lags():
    cov = np.diag([np.radians(0.05) ** 2] * 3 + [0.002**2] * 3)
    last = {}
    for jerk in (0.0, 10.0):
        kf = seeded(MotionFilterConfig(velocity_frame=VelocityFrame.WORLD, linear_jerk_noise=jerk), _cornering)
        for k in range(2, 101):
            kf.correct(k * 5_000, _cornering(k * 0.005), cov)
        last[jerk] = error(kf.predict(505_000), _cornering(0.505))[0]
        if jerk:
            assert np.allclose(kf._acc, [5.0, -5.0, 0.0], atol=0.1)
            copy = ConstantVelocityKalman(kf.config)
            copy.restore(kf.snapshot())
            assert np.array_equal(copy.predict(510_000), kf.predict(510_000))
    assert last[10.0] < 0.001 < last[0.0]


def test_a_covariance_without_positive_variances_is_not_fused():
    kf = seeded(MotionFilterConfig(velocity_frame=VelocityFrame.WORLD))
    bad = np.diag([1e-6] * 5 + [0.0])
    T = kf.correct(10_000, pose(0.01), bad)
    assert not kf.last_fused
    assert np.array_equal(T, seeded(MotionFilterConfig(velocity_frame=VelocityFrame.WORLD)).predict(10_000))
