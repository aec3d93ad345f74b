"""Constant-velocity Kalman filter: follows a constant twist, weighs noisy registrations, gates far ones, snapshots."""

import gtsam
import numpy as np

from evpose.tracker.motion_filter import ConstantVelocityKalman, MotionFilterConfig

XI = np.array([0.1, -0.2, 0.05, 1.0, 0.0, -0.5])  # rad/s, m/s
T0 = gtsam.Pose3(gtsam.Rot3.RzRyRx(0.1, 0.2, 0.3), gtsam.Point3(1, 2, 3))


def pose(t_s: float) -> np.ndarray:
    return T0.compose(gtsam.Pose3.Expmap(XI * t_s)).matrix()


def error(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    e = gtsam.Pose3.Logmap(gtsam.Pose3(A).between(gtsam.Pose3(B)))
    return float(np.linalg.norm(e[3:])), float(np.degrees(np.linalg.norm(e[:3])))


def seeded(config: MotionFilterConfig | None = None) -> ConstantVelocityKalman:
    kf = ConstantVelocityKalman(config)
    kf.reset(0, pose(0.0))
    kf.update(5_000, pose(0.005))  # seeds the twist, as TrackingSession does from ground truth
    return kf


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
