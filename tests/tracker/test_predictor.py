"""Motion predictors: constant velocity extrapolates a constant twist exactly."""

import gtsam
import numpy as np

from evpose.tracker.predictor import ConstantPosePredictor, ConstantVelocityPredictor


def test_constant_velocity_extrapolates_a_constant_twist():
    xi = np.array([0.1, -0.2, 0.05, 0.3, 0.0, -0.1])  # per second
    T0 = gtsam.Pose3(gtsam.Rot3.RzRyRx(0.1, 0.2, 0.3), gtsam.Point3(1, 2, 3))
    pose = lambda t: T0.compose(gtsam.Pose3.Expmap(xi * t)).matrix()  # noqa: E731
    p = ConstantVelocityPredictor()
    p.reset(0, pose(0.0))
    p.update(5_000, pose(0.005))
    assert np.allclose(p.predict(10_000), pose(0.010), atol=1e-12)
    assert np.allclose(p.twist(), xi, atol=1e-12)


def test_constant_velocity_with_one_pose_predicts_that_pose_and_snapshots():
    p = ConstantVelocityPredictor()
    T = np.eye(4)
    T[0, 3] = 1.0
    p.reset(0, T)
    assert np.array_equal(p.predict(1000), T)
    snap = p.snapshot()
    p.update(1000, np.eye(4))
    p.restore(snap)
    assert np.array_equal(p.predict(5000), T)


def test_constant_pose_predicts_the_last_update():
    p = ConstantPosePredictor()
    p.reset(0, np.eye(4))
    T = np.eye(4)
    T[1, 3] = 2.0
    p.update(10, T)
    assert np.array_equal(p.predict(99), T)


def test_windowed_constant_velocity_reproduces_a_constant_twist_exactly():
    xi = np.array([0.1, -0.2, 0.05, 0.3, 0.0, -0.1])
    T0 = gtsam.Pose3(gtsam.Rot3.RzRyRx(0.1, 0.2, 0.3), gtsam.Point3(1, 2, 3))
    pose = lambda t: T0.compose(gtsam.Pose3.Expmap(xi * t)).matrix()  # noqa: E731
    p = ConstantVelocityPredictor(window_us=30_000)
    p.reset(0, pose(0.0))
    for k in range(1, 10):
        p.update(k * 5_000, pose(k * 0.005))
    assert np.allclose(p.twist(), xi, atol=1e-9)
    assert np.allclose(p.predict(50_000), pose(0.050), atol=1e-9)


def test_windowed_velocity_is_less_noisy_than_the_two_pose_velocity():
    rng = np.random.default_rng(1)
    xi = np.array([0.0, 0.0, 0.0, 2.0, 0.0, 0.0])
    pose = lambda t, n: (gtsam.Pose3.Expmap(xi * t) * gtsam.Pose3.Expmap(np.r_[0, 0, 0, n])).matrix()  # noqa: E731
    errs = {0: [], 40_000: []}
    for window in errs:
        p = ConstantVelocityPredictor(window_us=window)
        p.reset(0, pose(0.0, np.zeros(3)))
        for k in range(1, 100):
            p.update(k * 5_000, pose(k * 0.005, rng.normal(0, 0.005, 3)))
            errs[window].append(np.linalg.norm(p.twist()[3:] - xi[3:]))
    assert np.mean(errs[40_000][10:]) < 0.3 * np.mean(errs[0][10:])
