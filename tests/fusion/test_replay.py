"""Replaying a fusion's recorded inputs: the same estimates as the run, plus smoothed ones from the window."""

import numpy as np

from evpose.fusion import FusionConfig, FusionMotionPredictor, make_fusion
from evpose.fusion.replay import FusionInputs, replay_fusion

from fusion_helpers import WHITE, make_motion, noisy_registrations, pose_errors


def _flight(calibration):
    m = make_motion(duration_s=0.4, imu_rate_hz=500.0, accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=2)
    t0 = m.config.t0_us
    times = t0 + np.arange(5000, 400_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=3)
    regs[40] = None  # a failed registration is replayed as one
    start = (t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    return m, times, gt, regs, cov, start


def test_recorded_inputs_replay_to_the_same_estimates_and_the_window_smooths(calibration):
    m, times, gt, regs, cov, (t0, T0, v0) = _flight(calibration)
    cfg = FusionConfig(window_states=10, **WHITE)
    motion = FusionMotionPredictor(make_fusion(cfg, calibration), m.imu(), v0)
    motion.reset(t0, T0)
    inputs = FusionInputs(t0, T0, v0)
    motion.input_log = inputs.reports
    online = [motion.report(int(t), regs[k], None if regs[k] is None else cov).T_world_cam for k, t in enumerate(times)]
    assert len(inputs.reports) == len(times) and inputs.reports[40][1] is None and inputs.reports[40][2] is None

    out = replay_fusion(make_fusion(cfg, calibration), m.imu(), inputs, lagged=True)
    t_on, T_on = out["online"]
    assert np.array_equal(t_on, times) and np.array_equal(T_on, np.array(online))
    t_lag, T_lag = out["lagged"]
    assert np.array_equal(t_lag, times)  # every state gets its estimate from when it was the oldest of the window
    t_win, T_win = out["window"]
    assert np.array_equal(t_win, times[-10:]) and np.array_equal(T_win[-1], T_on[-1])
    # Smoothed estimates have seen later registrations: on white noise they are better than the online ones.
    err = lambda T: np.mean([pose_errors(T[k], gt.matrix(k))[0] for k in range(20, len(times) - 10)])
    assert err(T_lag) < err(T_on)


def test_window_poses_hold_the_newest_states_oldest_first(calibration):
    m, times, gt, regs, cov, (t0, T0, v0) = _flight(calibration)
    f = make_fusion(FusionConfig(window_states=5, **WHITE), calibration)
    f.add_imu(m.imu())
    f.initialize(t0, T0, v0)
    t, T = f.window_poses()
    assert t.tolist() == [t0] and np.allclose(T[0], T0, atol=1e-9)
    for k in range(3):
        s = f.update(int(times[k]), regs[k], cov)
    t, T = f.window_poses()
    assert t.tolist() == [t0] + times[:3].tolist() and np.array_equal(T[-1], s.T_world_cam)
    for k in range(3, 12):
        s = f.update(int(times[k]), regs[k], cov)
    t, T = f.window_poses()
    assert t.tolist() == times[7:12].tolist() and T.shape == (5, 4, 4)


def test_error_study_compares_estimators_on_the_same_inputs_and_dead_reckons_with_true_biases(calibration):
    from evpose.fusion.replay import fusion_error_study

    m = make_motion(duration_s=0.4, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015), seed=4)
    t0 = m.config.t0_us
    times = t0 + np.arange(5000, 400_000, 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=5)
    start = m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0)
    inputs = FusionInputs(t0, start, m.camera_velocity([t0], calibration.T_cam_imu)[0],
                          [(int(t), regs[k], cov) for k, t in enumerate(times)])
    out = fusion_error_study(calibration, m.imu(), inputs, gt, (np.array([0.08, -0.05, 0.1]), np.array([0.01, -0.02, 0.015])))
    for name in ("replay_online", "fixed_lag_smoothed", "batch_smoothed", "ekf_online"):
        assert 0.0 < out[f"{name}_ate_mm"] < 10.0 and out[f"{name}_are_deg"] < 0.5
    # Exact IMU readings, known biases and start: dead reckoning is exact to integration error.
    assert out["imu_dead_reckoning_true_biases_ate_mm"] < 0.1


def test_smoothed_trajectory_holds_every_state_and_beats_the_online_estimate_on_white_noise(calibration):
    from evpose.fusion.replay import smoothed_trajectory

    m, times, gt, regs, cov, (t0, T0, v0) = _flight(calibration)
    inputs = FusionInputs(t0, T0, v0, [(int(t), regs[k], None if regs[k] is None else cov) for k, t in enumerate(times)])
    cfg = FusionConfig(**WHITE)
    online = replay_fusion(make_fusion(cfg, calibration), m.imu(), inputs)["online"][1]
    traj = smoothed_trajectory(cfg, calibration, m.imu(), inputs, lag_states=40)
    assert np.array_equal(traj.t, times)
    smoothed = traj.matrices()
    err = lambda T: np.sqrt(np.mean([pose_errors(T[k], gt.matrix(k))[0] ** 2 for k in range(len(times))]))
    assert err(smoothed) < 0.8 * err(online)
    # Deterministic: the same inputs give the same trajectory, bit for bit.
    assert np.array_equal(smoothed, smoothed_trajectory(cfg, calibration, m.imu(), inputs, lag_states=40).matrices())


def test_error_band_study_passes_slow_registration_errors_and_removes_fast_ones(calibration):
    # Registrations carrying a slow drift (a 10 mm ramp over the flight, like the landing's wander) plus 3 mm white
    # noise: fed only the fast part the fusion lands far closer to the truth than fed only the slow part.
    from evpose.fusion.registration_errors import poses_with_errors
    from evpose.fusion.replay import error_band_study

    m, times, gt, regs, cov, (t0, T0, v0) = _flight(calibration)
    rng = np.random.default_rng(7)
    ramp = np.linspace(0.0, 1.0, len(times))[:, None] * np.array([0.0, 0.0, 0.0, 0.01, -0.01, 0.005])
    e = ramp + np.c_[np.zeros((len(times), 3)), rng.normal(0, 0.003, (len(times), 3))]
    poses = poses_with_errors(times, e, gt)
    cov = np.diag([1e-6] * 3 + [0.003**2] * 3)
    inputs = FusionInputs(t0, T0, v0, [(int(t), None if k == 40 else poses[k], None if k == 40 else cov) for k, t in enumerate(times)])
    out = error_band_study(FusionConfig(**WHITE), calibration, m.imu(), inputs, gt, windows=(10,))
    assert out["fast_10_online_ate_mm"] < 0.5 * out["slow_10_online_ate_mm"]
    assert out["slow_10_online_ate_mm"] > 0.5 * out["slow_10_registrations_ate_mm"]  # the drift reaches the output
    assert out["fast_10_registrations_ate_mm"] < out["slow_10_registrations_ate_mm"]
    assert out == error_band_study(FusionConfig(**WHITE), calibration, m.imu(), inputs, gt, windows=(10,))  # deterministic
