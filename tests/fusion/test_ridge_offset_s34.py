"""The registration offset along the shift / tilt ridges (``FusionConfig.registration_offset_tau_s``): a Gauss-Markov
state in the factor graph through which the registrations measure the pose."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.errors import ConfigError
from evpose.fusion.config import FusionConfig, RegistrationErrorModel
from evpose.fusion.factor_graph import FactorGraphFusion
from evpose.fusion.state import Extrinsic
from evpose.fusion.registration_offset import OFF_RIDGE_SHARE, offset_key, ridge_part, split_ridge, stationary_covariance

from fusion_helpers import make_motion, update_with_replay

H = 4.0
"""Height the synthetic ridge is made for, m: a shift ``x`` across the optical axis looks like a tilt ``x / H``."""


def _ridge_covariance():
    """A registration covariance (rotation rad, translation m, camera frame) with two ridges: shift x against tilt
    about y, shift y against tilt about x (the landing camera looks down its z axis)."""
    s_r, s_t = 2e-3, 8e-3
    C = np.diag([s_r**2] * 3 + [s_t**2] * 3)
    C[1, 3] = C[3, 1] = 0.97 * s_r * s_t
    C[0, 4] = C[4, 0] = -0.97 * s_r * s_t
    return C


def _ridge_unit(C):
    """One standard deviation of ``C`` along its largest correlation eigen-direction (the x / tilt-about-y ridge)."""
    d = np.sqrt(np.diag(C))
    w, V = np.linalg.eigh(C / np.outer(d, d))
    u = V[:, -1] * d * np.sqrt(w[-1])
    return u if u[3] > 0 else -u


def _fly(calibration, tau_s, slow_sigmas=4.0, duration_s=1.5, snapshot_at=None, seed=1):
    """Fused states of a flight whose registrations carry white noise (their covariance less the offset's share of its
    ridges) plus a slow offset of
    ``slow_sigmas`` standard deviations along the x / tilt ridge (constant); with ``snapshot_at`` also the states after a
    snapshot there, restored and fed the same updates again. Returns (camera-frame ridge errors of the fused states,
    states, states again, fusion)."""
    m = make_motion(duration_s=duration_s, imu_rate_hz=500.0, seed=3)
    config = FusionConfig(registration_covariance_scale=1.0, registration_startup_s=0.0, registration_offset_tau_s=tau_s,
                          registration_offset_ratio=slow_sigmas**2)
    f = FactorGraphFusion(config, calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    times = t0 + np.arange(5000, int(duration_s * 1e6), 5000)
    gt = m.camera_trajectory(times, calibration.T_cam_imu)
    C = _ridge_covariance()
    slow = slow_sigmas * _ridge_unit(C)
    white_part, _ = split_ridge(slow_sigmas**2, C, C)  # what the offset model leaves white; the same data for both models
    rng = np.random.default_rng(seed)
    regs = []
    for k in range(len(times)):
        e = rng.multivariate_normal(np.zeros(6), white_part) + slow
        T = gt.matrix(k).copy()
        T[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(e[:3]).as_matrix()
        T[:3, 3] += T[:3, :3] @ e[3:]
        regs.append(T)
    states, again = update_with_replay(f, times, regs, C, snapshot_at)
    ridge = []
    for k, s in enumerate(states):
        G = gt.matrix(k)
        t_err = G[:3, :3].T @ (s.T_world_cam[:3, 3] - G[:3, 3])
        r_err = Rotation.from_matrix(G[:3, :3].T @ s.T_world_cam[:3, :3]).as_rotvec()
        ridge.append(np.r_[r_err, t_err] @ slow / (slow @ slow))  # in units of the injected offset
    return np.array(ridge), states, again, f


def test_the_offset_shares_a_slow_ridge_error_with_the_pose_only_while_the_start_holds_it(calibration):
    white, _, _, _ = _fly(calibration, 0.0, duration_s=0.5)
    offset, _, _, f = _fly(calibration, 2.0, duration_s=0.5)
    # One registration weighs as without the offset (the offset shares the ridge variance, not adds to it) ...
    assert abs(offset[0] - white[0]) < 0.01 and white[0] > 0.35
    # ... but a run of them does not average the slow part away: the pose moves onto the ridge more slowly ...
    assert offset[5:15].mean() < white[5:15].mean() - 0.05
    # ... and the offset holds part of the error (metres; 32 mm injected along the ridge).
    O = f.smoother.calculateEstimatePose3(offset_key(f.index)).matrix()
    assert 1e-3 < np.linalg.norm(O[:3, 3]) < 0.032
    # Later the pose (its initial velocity and biases free) is on the ridge as well: a slow error the IMU could tell
    # from motion only with a tighter start, which the landing's fusion does not have either.
    assert offset[-20:].mean() > 0.9 and white[-20:].mean() > 0.9


def test_the_stationary_covariance_lives_on_the_two_ridges():
    C = _ridge_covariance()
    R = ridge_part(C)
    w = np.linalg.eigvalsh(R)
    assert np.sum(w > 1e-3 * w.max()) == 2  # rank 2: the two ridges
    u = _ridge_unit(C)
    assert np.allclose(R @ np.linalg.pinv(R) @ u, u)  # the x / tilt-about-y ridge is in its range
    strong = np.array([0.0, H, 0.0, -1.0, 0.0, 0.0])  # H tilt - shift: what the image pins down (off the ridge)
    assert strong @ R @ strong < 0.05 * strong @ C @ strong
    # At the identity pose no frame change: ratio times the ridge part plus the small off-ridge share.
    same = Extrinsic(np.eye(4))
    P = stationary_covariance(9.0, C, same, np.eye(4))
    assert np.allclose(P, 9.0 * R + OFF_RIDGE_SHARE * C)
    # At another pose it is the same covariance carried by the pose's adjoint (a world-frame offset).
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_matrix()
    T[:3, 3] = [1.0, -2.0, 5.0]
    P2 = stationary_covariance(9.0, C, same, T)
    assert not np.allclose(P2, P) and np.all(np.linalg.eigvalsh(P2) > 0)
    # Shared with the registration factor: its ridge variance falls to 1 / (1 + r), off the ridges it stays.
    white, slow = split_ridge(3.0, C, C)
    assert np.allclose(white, C - 0.75 * R) and np.allclose(slow, C / 4.0)
    assert np.isclose(strong @ white @ strong, strong @ C @ strong, rtol=0.05)
    u_w = np.linalg.solve(C, u)  # the ridge's variance as the registration's information sees it
    assert np.isclose(u @ np.linalg.solve(white, u), 4.0 * (u @ u_w), rtol=0.05)


def test_a_snapshot_restores_the_offset_chain_bit_for_bit(calibration):
    _, states, again, _ = _fly(calibration, 0.5, duration_s=0.3, snapshot_at=25)
    for a, b in zip(states[25:], again):
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.gyro_bias, b.gyro_bias)


def test_a_failed_registration_carries_the_chain_on_and_the_default_has_no_offset(calibration):
    m = make_motion(duration_s=0.3, imu_rate_hz=500.0, seed=3)
    t0 = m.config.t0_us
    times = t0 + np.arange(5000, 300000, 5000)
    gt = m.camera_trajectory(times, calibration.T_cam_imu)
    for tau in (0.0, 0.5):
        f = FactorGraphFusion(FusionConfig(registration_offset_tau_s=tau), calibration)
        f.add_imu(m.imu())
        f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
        for k, t in enumerate(times):
            s = f.update(int(t), None if k in (20, 21) else gt.matrix(k), _ridge_covariance())
            assert np.isfinite(s.T_world_cam).all()
        keys = set(f.smoother.isam.getLinearizationPoint().keys())
        has_offsets = {offset_key(j) for j in range(f.index - 3, f.index + 1)} <= keys
        assert has_offsets == (tau > 0)
        if tau > 0:
            assert f.offset.last[0] == f.index and offset_key(20) not in keys


def test_a_bad_offset_configuration_is_refused():
    with pytest.raises(ConfigError):
        FusionConfig(registration_offset_tau_s=-0.1).validate()
    with pytest.raises(ConfigError):
        FusionConfig(registration_offset_tau_s=0.5, registration_offset_ratio=0.0).validate()
    with pytest.raises(ConfigError):
        FusionConfig(registration_offset_tau_s=0.5, registration_error_model=RegistrationErrorModel.AR1_BETWEEN).validate()


@pytest.mark.parametrize("n", [1, 2, 3])
def test_startup_inflation_widens_as_many_directions_as_configured(n):
    from evpose.fusion.startup import startup_inflated

    C = _ridge_covariance()
    config = FusionConfig(registration_startup_s=0.5, registration_startup_inflation=10.0, registration_startup_directions=n)
    W = startup_inflated(config, 0, 100_000, C)
    d = np.sqrt(np.diag(C))
    before = np.linalg.eigvalsh(C / np.outer(d, d))
    after = np.linalg.eigvalsh(W / np.outer(d, d))
    # the n largest correlation eigenvalues times 10, the others as they were
    assert np.allclose(np.sort(after), np.sort(np.r_[before[:-n], 10.0 * before[-n:]]))
    with pytest.raises(ConfigError):
        FusionConfig(registration_startup_directions=0).validate()
