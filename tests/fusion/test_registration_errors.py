"""Registration error figures: calibration (NEES), time correlation, tilt/shift coupling and conditioning on rotation."""

import numpy as np
import pytest

from evpose.core.trajectory import Trajectory
from evpose.fusion.registration_errors import (
    CHI2_6_MEDIAN,
    analyse_registration_errors,
    integrated_autocorrelation,
    pose_error_vectors,
    poses_with_errors,
    slow_part,
)


def _ar1(rng, n, phi, shape=()):
    """Unit-variance AR(1) series of coefficient ``phi`` (integrated autocorrelation time (1 + phi) / (1 - phi))."""
    x = np.zeros((n,) + shape)
    x[0] = rng.standard_normal(shape)
    for k in range(1, n):
        x[k] = phi * x[k - 1] + np.sqrt(1 - phi * phi) * rng.standard_normal(shape)
    return x


def test_white_errors_have_an_autocorrelation_time_of_one_and_correlated_ones_a_longer_one():
    rng = np.random.default_rng(0)
    assert integrated_autocorrelation(rng.standard_normal(4000)) == pytest.approx(1.0, abs=0.3)
    tau = integrated_autocorrelation(_ar1(rng, 20000, 0.9))
    assert tau == pytest.approx(19.0, rel=0.25)  # (1 + 0.9) / (1 - 0.9)
    assert integrated_autocorrelation(np.ones(10)) == 1.0  # no variance: nothing to correlate


def test_calibrated_errors_give_the_chi_square_median_and_tilt_shift_coupling_is_found_and_removed():
    # Errors drawn from their covariance: rotation about y and translation x strongly coupled (slope -4 m/rad),
    # as a downward camera's registrations over a plane are.
    rng = np.random.default_rng(1)
    A = np.eye(6) * 1e-3
    A[3, 1] = -4e-3  # tx = -4 * ry + small
    C = A @ A.T
    n = 3000
    e = rng.standard_normal((n, 6)) @ A.T
    out = analyse_registration_errors(e, np.repeat(C[None], n, 0))
    assert out["nees_median"] == pytest.approx(CHI2_6_MEDIAN, rel=0.1)
    assert out["slope_tx_per_ry_empirical_m_per_rad"] == pytest.approx(-4.0, rel=0.1)
    assert out["slope_tx_per_ry_covariance_m_per_rad"] == pytest.approx(-4.0, rel=0.01)
    assert out["correlation_tx_per_ry_covariance"] < -0.95
    # Knowing the rotation removes the coupled part: tx drops to its own 1 mm.
    assert out["rms_tx_mm"] > 3.5 and out["rms_tx_given_true_rotation_mm"] == pytest.approx(1.0, rel=0.1)
    with pytest.raises(ValueError):
        analyse_registration_errors(e[:, :5], np.repeat(C[None], n, 0))


def test_pose_error_vectors_are_in_the_camera_frame():
    t = np.array([0, 1_000_000], np.int64)
    # Camera looking down (rotated 180 deg about x): a world +z offset is a camera -z error.
    q = np.array([[1.0, 0, 0, 0]] * 2)
    gt = Trajectory.from_arrays(t, np.zeros((2, 3)), q)
    T = gt.matrices().copy()
    T[:, 2, 3] += 0.01
    e = pose_error_vectors(t, T, gt)
    assert np.allclose(e[:, :3], 0) and np.allclose(e[:, 3:], [0, 0, -0.01])


def test_poses_with_errors_invert_pose_error_vectors():
    rng = np.random.default_rng(3)
    t = np.arange(0, 1_000_000, 50_000, dtype=np.int64)
    q = rng.standard_normal((len(t), 4))
    gt = Trajectory.from_arrays(t, rng.normal(0, 2.0, (len(t), 3)), q / np.linalg.norm(q, axis=1, keepdims=True))
    e = np.c_[rng.normal(0, 0.01, (len(t), 3)), rng.normal(0, 0.02, (len(t), 3))]
    assert np.allclose(pose_error_vectors(t, poses_with_errors(t, e, gt), gt), e, atol=1e-12)


def test_slow_part_is_a_centred_moving_average_that_keeps_ramps_and_removes_alternation():
    n = 40
    ramp = np.outer(np.arange(n, dtype=float), np.ones(6))
    s = slow_part(ramp, 5)
    assert s.shape == ramp.shape and np.allclose(s[2:-2], ramp[2:-2])  # centred: a linear trend passes unchanged
    assert np.allclose(s[0], (0 + 0 + 0 + 1 + 2) / 5)  # the ends are padded with the end values
    alternating = np.outer((-1.0) ** np.arange(n), np.ones(6))
    assert np.abs(slow_part(alternating, 2)[1:]).max() < 1e-12  # a two-sample average cancels the fastest swing
