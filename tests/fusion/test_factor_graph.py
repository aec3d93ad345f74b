"""Factor-graph fusion (iSAM2 + fixed-lag window) on an analytic flight with exact IMU."""

import numpy as np
import pytest

from evpose.errors import ConfigError
from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import FactorGraphFusion

from fusion_helpers import WHITE, make_motion, noisy_registrations, pose_errors

BIAS_A = (0.08, -0.05, 0.1)
BIAS_G = (0.01, -0.02, 0.015)


def _noisy_motion(duration_s, seed=0):
    return make_motion(duration_s=duration_s, imu_rate_hz=500.0, acc_bias=BIAS_A, gyro_bias=BIAS_G,
                       accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=seed)


def _start(motion, calibration, config=None):
    f = FactorGraphFusion(config or FusionConfig(**WHITE), calibration)
    f.add_imu(motion.imu())
    t0 = motion.config.t0_us
    gt0 = motion.camera_trajectory([t0], calibration.T_cam_imu)
    f.initialize(t0, gt0.matrix(0), motion.camera_velocity([t0], calibration.T_cam_imu)[0])
    return f


def test_fusion_is_more_accurate_than_the_registrations(calibration):
    m = _noisy_motion(1.5)
    f = _start(m, calibration)
    times = m.config.t0_us + np.arange(5000, 1_500_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=1)
    fused, raw = [], []
    for k, t in enumerate(times):
        s = f.update(int(t), regs[k], cov)
        assert not s.degraded and s.covariance.shape == (6, 6)
        fused.append(pose_errors(s.T_world_cam, gt.matrix(k)))
        raw.append(pose_errors(regs[k], gt.matrix(k)))
    fused, raw = np.array(fused[60:]), np.array(raw[60:])
    rms = lambda a: np.sqrt(np.mean(a**2, axis=0))  # noqa: E731
    assert rms(fused)[0] < 0.5 * rms(raw)[0]
    assert rms(fused)[1] < 0.5 * rms(raw)[1]
    # The reported covariance is in the right range (translation sigma within 3x of the real error).
    sig = np.sqrt(np.diag(s.covariance)[3:]).mean()
    assert rms(fused)[0] / 3 < sig * np.sqrt(3) < 3 * rms(fused)[0]


def test_fusion_recovers_from_a_perturbed_registration(calibration):
    m = _noisy_motion(1.0)
    f = _start(m, calibration)
    times = m.config.t0_us + np.arange(5000, 1_000_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=2)
    bad = 100
    regs[bad] = regs[bad].copy()
    regs[bad][:3, 3] += np.array([0.15, -0.1, 0.05])  # an 19 cm outlier
    errs = []
    for k, t in enumerate(times):
        errs.append(pose_errors(f.update(int(t), regs[k], cov).T_world_cam, gt.matrix(k))[0])
    errs = np.array(errs)
    assert errs[bad] < 0.01  # the robust factor keeps the outlier from dragging the estimate
    assert np.all(errs[bad + 10 :] < 0.005)


def test_gyro_bias_is_estimated_on_a_long_run(calibration):
    m = _noisy_motion(6.0, seed=4)
    f = _start(m, calibration, FusionConfig(compute_covariance=False, **WHITE))
    times = m.config.t0_us + np.arange(20_000, 6_000_000, 20_000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.003, np.radians(0.2), seed=3)
    for k, t in enumerate(times):
        s = f.update(int(t), regs[k], cov)
    bg = np.array(BIAS_G)
    assert np.all(np.abs(s.gyro_bias - bg) < 0.2 * np.abs(bg)), s.gyro_bias
    assert np.linalg.norm(s.acc_bias - np.array(BIAS_A)) < 0.5 * np.linalg.norm(BIAS_A), s.acc_bias


def test_tracking_loss_is_bridged_by_the_imu_and_reacquired(calibration):
    m = _noisy_motion(1.5)
    f = _start(m, calibration)
    times = m.config.t0_us + np.arange(5000, 1_500_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=5)
    lost = (times > m.config.t0_us + 600_000) & (times < m.config.t0_us + 900_000)
    states = [f.update(int(t), None if lost[k] else regs[k], cov) for k, t in enumerate(times)]
    degraded = np.array([s.degraded for s in states])
    assert np.array_equal(degraded, lost)
    errs = np.array([pose_errors(s.T_world_cam, gt.matrix(k))[0] for k, s in enumerate(states)])
    assert errs[lost].max() < 0.02  # 0.3 s of IMU-only propagation with estimated biases
    sig_lost = [np.sqrt(np.trace(s.covariance[3:, 3:])) for s in states if s.degraded]
    assert sig_lost[-1] > 3 * sig_lost[0]  # the uncertainty grows honestly while lost
    after = np.flatnonzero(~lost & (np.arange(len(times)) > np.flatnonzero(lost)[-1]))
    assert errs[after[0]] < 0.01 and np.all(errs[after[5:]] < 0.004)


def test_predict_and_imu_rate_poses_follow_the_truth_without_changing_the_state(calibration):
    m = _noisy_motion(0.6)
    f = _start(m, calibration)
    g = _start(m, calibration)
    times = m.config.t0_us + np.arange(5000, 500_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=6)
    for k, t in enumerate(times):
        f.predict(int(t) - 2500)  # predictions in between must not influence the estimates
        a, b = f.update(int(t), regs[k], cov), g.update(int(t), regs[k], cov)
        assert np.array_equal(a.T_world_cam, b.T_world_cam)
    t_last = int(times[-1])
    p = f.predict(t_last + 3000)
    truth = m.camera_trajectory([t_last + 3000], calibration.T_cam_imu).matrix(0)
    assert pose_errors(p.T_world_cam, truth)[0] < 0.005
    traj = f.imu_rate_poses(int(times[-3]), t_last)
    assert len(traj) == 5  # 500 Hz IMU over 10 ms
    assert np.all(np.diff(traj.t) == 2000)
    truth = m.camera_trajectory(traj.t, calibration.T_cam_imu)
    assert np.max(np.linalg.norm(traj.position - truth.position, axis=1)) < 0.005


def _run_restore_and_rerun(f, m, calibration, clear_journal: bool = False):
    """Updates 0-39 (one without a registration), a snapshot, updates 40-59, a restore and updates 40-59 again:
    (first, second) results of 40-59."""
    times = m.config.t0_us + np.arange(5000, 500_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=7)
    for k in range(40):
        f.update(int(times[k]), None if k == 30 else regs[k], cov)
    snap = f.snapshot()
    first = [f.update(int(times[k]), regs[k], cov) for k in range(40, 60)]
    f.restore(snap)
    if clear_journal:
        f.smoother.journal = []
    return first, [f.update(int(times[k]), regs[k], cov) for k in range(40, 60)]


def test_snapshot_restore_reproduces_the_run_bit_for_bit(calibration):
    m = _noisy_motion(0.5)
    first, second = _run_restore_and_rerun(_start(m, calibration), m, calibration)
    for a, b in zip(first, second):
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.gyro_bias, b.gyro_bias)
        assert np.array_equal(a.covariance, b.covariance)


def test_update_before_initialize_and_bad_config_are_refused():
    with pytest.raises(RuntimeError):
        FactorGraphFusion().update(10, np.eye(4))
    with pytest.raises(ConfigError):
        FactorGraphFusion(FusionConfig(window_states=1))


def test_non_finite_registration_counts_as_failure_and_bad_covariance_falls_back(calibration):
    m = _noisy_motion(0.2)
    f = _start(m, calibration)
    t0 = m.config.t0_us
    gt = m.camera_trajectory([t0 + 10_000, t0 + 20_000], calibration.T_cam_imu)
    assert f.update(t0 + 10_000, np.full((4, 4), np.nan), None).degraded
    s = f.update(t0 + 20_000, gt.matrix(1), np.full((6, 6), np.nan))
    assert not s.degraded and np.isfinite(s.T_world_cam).all()


@pytest.mark.parametrize("backend", ["factor_graph", "ekf"])
def test_unknown_initial_velocity_is_estimated_within_a_fraction_of_a_second(backend, calibration):
    from evpose.fusion import make_fusion

    m = _noisy_motion(0.6)
    f = make_fusion(FusionConfig(backend=backend, compute_covariance=False, **WHITE), calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0))  # no velocity given
    times = t0 + np.arange(5000, 600_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=8)
    states = [f.update(int(t), regs[k], cov) for k, t in enumerate(times)]
    v_true = m.camera_velocity(times, calibration.T_cam_imu)
    assert np.linalg.norm(v_true[0]) > 0.5
    v_err = np.array([np.linalg.norm(s.velocity_world - v_true[k]) for k, s in enumerate(states)])
    assert np.all(v_err[60:] < 0.05)


def test_repeated_predictions_are_reused_but_follow_new_imu_and_new_states(calibration):
    m = _noisy_motion(0.2)
    f = _start(m, calibration)
    g = _start(m, calibration)
    t = m.config.t0_us + 20_000
    first = f.predict(t)
    first.T_world_cam[:] = 0.0  # callers own what they get
    assert np.array_equal(f.predict(t).T_world_cam, g.predict(t).T_world_cam)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, [t], 0.002, np.radians(0.1), seed=2)
    f.update(t, regs[0], cov)
    g.update(t, regs[0], cov)
    assert np.array_equal(f.predict(t + 5000).T_world_cam, g.predict(t + 5000).T_world_cam)

    # IMU arriving after a prediction changes the next one at the same time.
    imu = m.imu()
    t_cut = m.config.t0_us + 10_000
    h = FactorGraphFusion(FusionConfig(**WHITE), calibration)
    h.add_imu(imu[: int(np.searchsorted(imu.t, t_cut))])
    gt0 = m.camera_trajectory([m.config.t0_us], calibration.T_cam_imu)
    h.initialize(m.config.t0_us, gt0.matrix(0), m.camera_velocity([m.config.t0_us], calibration.T_cam_imu)[0])
    early = h.predict(t).T_world_cam
    h.add_imu(imu)
    late = h.predict(t).T_world_cam
    assert not np.array_equal(early, late)
    assert np.array_equal(late, _start(m, calibration).predict(t).T_world_cam)


def test_registration_covariance_scale_equals_feeding_the_scaled_covariance(calibration):
    m = _noisy_motion(0.2)
    times = m.config.t0_us + np.arange(5000, 200_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=2)
    a = _start(m, calibration, FusionConfig(registration_covariance_scale=30.0))
    b = _start(m, calibration, FusionConfig(**WHITE))
    for k, t in enumerate(times):
        sa, sb = a.update(int(t), regs[k], cov), b.update(int(t), regs[k], 30.0 * cov)
        assert np.array_equal(sa.T_world_cam, sb.T_world_cam)


def test_scaled_registration_covariance_lets_the_imu_smooth_correlated_registration_errors(calibration):
    # Registrations whose error wanders slowly (0.2 s correlation) plus a third as much white noise: a filter that
    # believes each covariance follows the noise; the scaled one lets the gyro average it out.
    m = _noisy_motion(2.0)
    times = m.config.t0_us + np.arange(5000, 2_000_000, 5000)
    gt, regs, cov = _ar1_registrations(m, calibration, times, np.exp(-1.0 / 40.0), seed=5, white_ratio=1 / 3)
    rot = {}
    for scale in (1.0, 30.0):
        f = _start(m, calibration, FusionConfig(registration_covariance_scale=scale))
        errs = np.array([pose_errors(f.update(int(t), regs[k], cov).T_world_cam, gt.matrix(k)) for k, t in enumerate(times)])
        rot[scale] = np.sqrt(np.mean(errs[100:, 1] ** 2))
    assert rot[30.0] < 0.9 * rot[1.0]


def test_relinearize_skip_and_covariance_scale_are_validated():
    with pytest.raises(ConfigError):
        FactorGraphFusion(FusionConfig(relinearize_skip=0))
    with pytest.raises(ConfigError):
        FactorGraphFusion(FusionConfig(registration_covariance_scale=0.0))
    for bad in ({"registration_ar_rho": 1.0}, {"registration_ar_rho": -0.1}, {"registration_ar_covariance_scale": 0.0},
                {"registration_ar_between_scale": 0.0}, {"init_sigma_acc_bias_vertical": -0.1}):
        with pytest.raises(ConfigError):
            FactorGraphFusion(FusionConfig(**bad))


def test_restore_at_a_late_step_reproduces_the_run_and_the_snapshot_stays_reusable(calibration):
    m = _noisy_motion(2.2)
    f = _start(m, calibration)
    times = m.config.t0_us + np.arange(5000, 2_200_000, 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=9)
    late = 400
    for k in range(late):
        f.update(int(times[k]), None if 350 <= k < 360 else regs[k], cov)
    snap = f.snapshot()
    assert "log" not in snap  # constant size: the window, not the inputs since initialisation
    first = [f.update(int(times[k]), regs[k], cov) for k in range(late, late + 20)]
    for _ in range(2):  # a snapshot restores the same state however often it is used
        g = FactorGraphFusion(FusionConfig(**WHITE), calibration)
        g.restore(snap)
        assert g.index == late and g.degraded is False
        again = [g.update(int(times[k]), regs[k], cov) for k in range(late, late + 20)]
        for a, b in zip(first, again):
            assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.velocity_world, b.velocity_world)
            assert np.array_equal(a.acc_bias, b.acc_bias) and np.array_equal(a.covariance, b.covariance)
        assert np.array_equal(g.predict(int(times[late + 19]) + 2000).T_world_cam, f.predict(int(times[late + 19]) + 2000).T_world_cam)


def test_snapshot_of_an_uninitialised_fusion_restores_to_uninitialised(calibration):
    m = _noisy_motion(0.2)
    f = FactorGraphFusion(FusionConfig(**WHITE), calibration)
    f.add_imu(m.imu())
    snap = f.snapshot()
    g = _start(m, calibration)
    g.restore(snap)
    assert not g.initialized
    with pytest.raises(RuntimeError):
        g.update(m.config.t0_us + 10_000, np.eye(4))


def test_registration_covariance_falls_back_to_the_default_sigmas_only_when_the_given_one_is_unusable():
    from evpose.fusion.factor_graph import registration_covariance

    c = FusionConfig(registration_covariance_scale=4.0)
    floor = np.eye(6) * c.registration_min_sigma**2
    default = np.diag([c.registration_default_sigma_rot**2] * 3 + [c.registration_default_sigma_trans**2] * 3) + floor
    good = np.diag([1e-6, 2e-6, 3e-6, 1e-4, 2e-4, 3e-4])
    np.testing.assert_array_equal(registration_covariance(c, good), good * 4.0 + floor)
    for bad in (None, np.full((6, 6), np.nan), -good):
        np.testing.assert_array_equal(registration_covariance(c, bad), default)


def test_cached_imu_prediction_equals_a_fresh_one_and_follows_new_imu_samples(calibration):
    """The NavState the motion prediction computed is reused for the new state's initial value at the same time, and
    recomputed once the buffer or the anchor changes."""
    m = _noisy_motion(0.3)
    full = m.imu()
    f = FactorGraphFusion(FusionConfig(**WHITE), calibration)
    f.add_imu(full.time_window(0, m.config.t0_us + 100_000))
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    p = f.propagator
    t = t0 + 150_000  # beyond the buffered IMU: the last measurement is held
    held = p.predict_nav(t)
    assert p.predict_nav(t) is held
    fresh = p.preintegration_to(t).predict(p.nav, p.bias)
    np.testing.assert_array_equal(held.pose().matrix(), fresh.pose().matrix())
    f.add_imu(full.time_window(t0 + 100_000, t0 + 300_000))  # new samples: the same time now integrates them
    updated = p.predict_nav(t)
    assert updated is not held and not np.array_equal(updated.pose().matrix(), held.pose().matrix())


def _ar1_registrations(m, calibration, times, rho, seed=5, white_ratio=0.1):
    """Registrations whose error is AR(1) per update (coefficient ``rho``) plus white noise of ``white_ratio`` times
    its standard deviation."""
    from scipy.spatial.transform import Rotation

    gt = m.camera_trajectory(times, calibration.T_cam_imu)
    rng = np.random.default_rng(seed)
    sig = np.array([np.radians(0.3)] * 3 + [0.005] * 3)
    off = np.zeros(6)
    regs = []
    for k in range(len(gt)):
        off = rho * off + np.sqrt(1 - rho * rho) * rng.normal(0, 1, 6) * sig
        e = off + rng.normal(0, 1, 6) * sig * white_ratio
        T = gt.matrix(k)
        T[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(e[:3]).as_matrix()
        T[:3, 3] += T[:3, :3] @ e[3:]
        regs.append(T)
    return gt, regs, np.diag(sig**2)


@pytest.mark.parametrize("model", ["ar1_whitened", "ar1_between"])
def test_ar1_error_models_beat_white_registrations_on_ar1_errors(model, calibration):
    from evpose.fusion.config import RegistrationErrorModel

    m = _noisy_motion(2.0)
    times = m.config.t0_us + np.arange(5000, 2_000_000, 5000)
    gt, regs, cov = _ar1_registrations(m, calibration, times, 0.95)
    trans = {}
    # Without the start-up widening (session 33's default): on this diagonal covariance it has no ridge to widen and
    # would widen two arbitrary directions of the first 0.5 s, which is not what is compared here.
    for name, cfg in (("white", FusionConfig(registration_covariance_scale=1.0, registration_startup_s=0.0)),
                      (model, FusionConfig(registration_error_model=RegistrationErrorModel(model), registration_ar_rho=0.95,
                                           registration_ar_covariance_scale=1.0 - 0.95**2, registration_startup_s=0.0))):
        f = _start(m, calibration, cfg)
        errs = np.array([pose_errors(f.update(int(t), regs[k], cov).T_world_cam, gt.matrix(k)) for k, t in enumerate(times)])
        trans[name] = np.sqrt(np.mean(errs[100:, 0] ** 2))
    assert trans[model] < 0.9 * trans["white"]


@pytest.mark.parametrize("model", ["ar1_whitened", "ar1_between"])
def test_ar1_error_models_restore_bit_for_bit_and_serialise(model, calibration):
    import gtsam

    from evpose.fusion.config import RegistrationErrorModel

    m = _noisy_motion(0.5)
    f = _start(m, calibration, FusionConfig(registration_error_model=RegistrationErrorModel(model)))
    first, second = _run_restore_and_rerun(f, m, calibration, clear_journal=True)
    for a, b in zip(first, second):
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.covariance, b.covariance)
    # The disk snapshots store the smoother's journal as gtsam-serialised graphs: the AR(1) factors must survive it.
    graphs = [e[1] for e in f.smoother.journal if e[0] == "update" and e[1] is not None]
    assert any(graphs[-1].at(i).__class__.__name__ in ("PriorFactorPose3", "BetweenFactorPose3") for i in range(graphs[-1].size()))
    for g in graphs[-3:]:
        back = gtsam.NonlinearFactorGraph()
        back.deserialize(g.serialize())
        assert back.size() == g.size() and back.equals(g, 1e-12)


def test_state_keys_are_gtsam_symbols():
    import gtsam

    f = FactorGraphFusion(FusionConfig())
    sh = gtsam.symbol_shorthand
    for i in (0, 1, 7, 123456):
        assert f._keys(i) == (sh.X(i), sh.V(i), sh.B(i))


def test_initial_bias_prior_is_diagonal_unless_a_vertical_sigma_is_set():
    from evpose.fusion.factor_graph import initial_bias_covariance

    assert initial_bias_covariance(FusionConfig(), np.eye(3)) is None
    c = FusionConfig(init_sigma_acc_bias=0.1, init_sigma_acc_bias_vertical=0.5, init_sigma_gyro_bias=0.01)
    R_world_imu = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # world z = IMU y
    P = initial_bias_covariance(c, R_world_imu)
    up = R_world_imu[2]
    across = np.array([1.0, 0.0, 0.0])
    assert up @ P[:3, :3] @ up == pytest.approx(0.25)
    assert across @ P[:3, :3] @ across == pytest.approx(0.01)
    np.testing.assert_allclose(P[3:, 3:], 1e-4 * np.eye(3))
    np.testing.assert_array_equal(P[:3, 3:], 0.0)
