"""Error-state EKF baseline: same inputs and interface as the factor graph."""

import numpy as np

from evpose.fusion.config import FusionConfig
from evpose.fusion.ekf import ErrorStateEkf

from fusion_helpers import WHITE, make_motion, noisy_registrations, pose_errors


def _run(calibration, duration_s, lost_span=None, seed=0):
    m = make_motion(duration_s=duration_s, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015),
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=seed)
    f = ErrorStateEkf(FusionConfig(**WHITE), calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    times = t0 + np.arange(5000, int(duration_s * 1e6), 5000)
    gt, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.005, np.radians(0.3), seed=seed + 1)
    lost = np.zeros(times.size, bool) if lost_span is None else (times > t0 + lost_span[0]) & (times < t0 + lost_span[1])
    states = [f.update(int(t), None if lost[k] else regs[k], cov) for k, t in enumerate(times)]
    return m, f, times, gt, regs, states, lost


def test_ekf_filters_noisy_registrations_and_estimates_gyro_bias(calibration):
    m, f, times, gt, regs, states, _ = _run(calibration, 3.0)
    fused = np.array([pose_errors(s.T_world_cam, gt.matrix(k)) for k, s in enumerate(states)])[100:]
    raw = np.array([pose_errors(regs[k], gt.matrix(k)) for k in range(len(states))])[100:]
    assert np.sqrt(np.mean(fused[:, 0] ** 2)) < 0.5 * np.sqrt(np.mean(raw[:, 0] ** 2))
    assert np.sqrt(np.mean(fused[:, 1] ** 2)) < 0.5 * np.sqrt(np.mean(raw[:, 1] ** 2))
    assert np.linalg.norm(states[-1].gyro_bias - np.array([0.01, -0.02, 0.015])) < 0.005
    assert states[-1].covariance.shape == (6, 6) and np.all(np.linalg.eigvalsh(states[-1].covariance) > 0)


def test_ekf_marks_degraded_poses_and_reacquires(calibration):
    m, f, times, gt, regs, states, lost = _run(calibration, 1.2, lost_span=(500_000, 800_000), seed=3)
    assert np.array_equal([s.degraded for s in states], lost)
    errs = np.array([pose_errors(s.T_world_cam, gt.matrix(k))[0] for k, s in enumerate(states)])
    assert errs[lost].max() < 0.03
    assert np.all(errs[np.flatnonzero(lost)[-1] + 10 :] < 0.01)


def test_ekf_snapshot_restore_is_exact(calibration):
    m, f, times, gt, regs, states, _ = _run(calibration, 0.3)
    snap = f.snapshot()
    t = int(times[-1]) + 5000
    a = f.update(t, regs[-1], None)
    f.restore(snap)
    b = f.update(t, regs[-1], None)
    assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.covariance, b.covariance)
    traj = f.imu_rate_poses(int(times[-2]), t)
    assert len(traj) > 0 and np.all(np.diff(traj.t) > 0)


def test_ekf_starts_with_the_vertical_accelerometer_bias_prior(calibration):
    from evpose.fusion.factor_graph import initial_bias_covariance

    m = make_motion(duration_s=0.1, imu_rate_hz=500.0)
    c = FusionConfig(**WHITE)
    c.init_sigma_acc_bias_vertical = 0.5
    f = ErrorStateEkf(c, calibration)
    f.add_imu(m.imu())
    T0 = m.camera_trajectory([m.config.t0_us], calibration.T_cam_imu).matrix(0)
    f.initialize(m.config.t0_us, T0)
    np.testing.assert_allclose(f.state.P[9:, 9:], initial_bias_covariance(c, f.extrinsic.imu_pose(T0)[:3, :3]))
    assert not np.allclose(f.state.P[9:12, 9:12], np.diag(np.diag(f.state.P[9:12, 9:12])))
