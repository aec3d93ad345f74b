"""The gyroscope-bias hold (``FusionConfig.gyro_bias_hold_s``): held at its initial value for the hold, then learnt."""

import numpy as np
import pytest

from evpose.errors import ConfigError
from evpose.fusion.config import FusionBackend, FusionConfig
from evpose.fusion.ekf import ErrorStateEkf
from evpose.fusion.factor_graph import FactorGraphFusion

from fusion_helpers import WHITE, make_motion, noisy_registrations, update_with_replay

BIAS_G = (0.01, -0.02, 0.015)
HOLD_S = 0.2


def _run(backend, calibration, hold_s, duration_s=1.5, snapshot_at=None):
    """Fused states of a flight with a biased gyroscope and 5 ms registrations; with ``snapshot_at`` (an update index)
    also the states after a snapshot there, restored and fed the same updates again."""
    m = make_motion(duration_s=duration_s, imu_rate_hz=500.0, acc_bias=(0.0, 0.0, 0.0), gyro_bias=BIAS_G,
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=3)
    config = FusionConfig(backend=backend, gyro_bias_hold_s=hold_s, **WHITE)
    f = (FactorGraphFusion if backend is FusionBackend.FACTOR_GRAPH else ErrorStateEkf)(config, calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    times = m.config.t0_us + np.arange(5000, int(duration_s * 1e6), 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=4)
    states, again = update_with_replay(f, times, regs, cov, snapshot_at)
    return (times - t0) * 1e-6, states, again


@pytest.mark.parametrize("backend", [FusionBackend.FACTOR_GRAPH, FusionBackend.EKF])
def test_gyro_bias_is_held_for_the_hold_then_learnt(backend, calibration):
    t, held, _ = _run(backend, calibration, HOLD_S)
    _, free, _ = _run(backend, calibration, 0.0)
    bg_held = np.array([s.gyro_bias for s in held])
    bg_free = np.array([s.gyro_bias for s in free])
    during = t < HOLD_S - 1e-9
    # Held at its initial value (zero) through the hold, while without the hold it is already being learnt.
    assert np.abs(bg_held[during]).max() < 2e-4
    assert np.abs(bg_free[during][-1]).max() > 2e-3
    # Released at the first state at or after the hold: it moves at once and is learnt afterwards.
    first = int(np.flatnonzero(~during)[0])
    assert np.abs(bg_held[first + 10]).max() > 1e-3
    err = np.abs(bg_held[-1] - np.array(BIAS_G))
    assert np.all(err < 0.3 * np.abs(BIAS_G)), bg_held[-1]


@pytest.mark.parametrize("backend", [FusionBackend.FACTOR_GRAPH, FusionBackend.EKF])
def test_a_snapshot_taken_during_the_hold_restores_the_release_bit_for_bit(backend, calibration):
    _, states, again = _run(backend, calibration, HOLD_S, duration_s=0.4, snapshot_at=20)
    for a, b in zip(states[20:], again):
        assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.gyro_bias, b.gyro_bias)


def test_a_negative_hold_or_a_non_positive_hold_sigma_is_refused():
    with pytest.raises(ConfigError):
        FusionConfig(gyro_bias_hold_s=-0.1).validate()
    with pytest.raises(ConfigError):
        FusionConfig(gyro_bias_hold_s=0.2, gyro_bias_hold_sigma=0.0).validate()


def _ridge_covariance():
    """A registration covariance (rotation rad, translation m) whose shift / tilt pairs are strongly correlated."""
    C = np.diag([1e-6, 1e-6, 1e-6, 1.6e-5, 1.6e-5, 1.6e-5])
    C[1, 3] = C[3, 1] = -0.95 * 1e-3 * 4e-3  # x against tilt about y
    C[0, 4] = C[4, 0] = 0.9 * 1e-3 * 4e-3  # y against tilt about x
    return C


def test_startup_inflation_widens_only_the_two_ridges_and_only_during_the_startup():
    from evpose.fusion.startup import startup_inflated

    config = FusionConfig(registration_startup_s=0.3, registration_startup_inflation=10.0)
    C = _ridge_covariance()
    D = startup_inflated(config, 1_000_000, 1_200_000, C)
    w, V = np.linalg.eigh(C / np.sqrt(np.outer(np.diag(C), np.diag(C))))
    Dn = D / np.sqrt(np.outer(np.diag(C), np.diag(C)))
    # Along the correlation matrix's two largest eigen-directions the variance is 10x, along the others unchanged.
    for k in range(6):
        ratio = V[:, k] @ Dn @ V[:, k] / w[k]
        assert ratio == pytest.approx(10.0 if k >= 4 else 1.0, rel=1e-9)
    # What the images observe (x + tilt about y, in the correlation's units) keeps its variance.
    strong = np.array([0.0, 1.0, 0.0, 1.0, 0.0, 0.0]) / np.sqrt(2.0)
    assert strong @ Dn @ strong == pytest.approx(strong @ (C / np.sqrt(np.outer(np.diag(C), np.diag(C)))) @ strong, rel=1e-6)
    # After the startup, before any start, or off: the covariance as given.
    assert startup_inflated(config, 1_000_000, 1_300_000, C) is C
    assert startup_inflated(config, None, 1_200_000, C) is C
    assert startup_inflated(FusionConfig(registration_startup_s=0.0), 1_000_000, 1_000_001, C) is C
    # ``registration_ridge_scale``: the same two directions scaled after the startup.
    later = startup_inflated(FusionConfig(registration_startup_s=0.3, registration_ridge_scale=0.5), 1_000_000, 1_300_000, C)
    Ln = later / np.sqrt(np.outer(np.diag(C), np.diag(C)))
    assert [V[:, k] @ Ln @ V[:, k] / w[k] for k in (3, 4, 5)] == pytest.approx([1.0, 0.5, 0.5], rel=1e-9)


@pytest.mark.parametrize("backend", [FusionBackend.FACTOR_GRAPH, FusionBackend.EKF])
def test_startup_inflation_changes_the_fusion_only_during_the_startup(backend, calibration):
    """Fed the same registrations, a fusion with the startup widening differs from one without during the startup
    and fuses the later registrations with their own covariance (the states then converge)."""
    m = make_motion(duration_s=0.6, imu_rate_hz=500.0, acc_bias=(0.0, 0.0, 0.0), gyro_bias=BIAS_G,
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=3)
    t0 = m.config.t0_us
    times = t0 + np.arange(5000, 600_000, 5000)
    _, regs, _ = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=4)
    cov = _ridge_covariance()
    out = {}
    for s in (0.0, 0.1):
        config = FusionConfig(backend=backend, registration_startup_s=s, registration_startup_inflation=100.0, **WHITE)
        f = (FactorGraphFusion if backend is FusionBackend.FACTOR_GRAPH else ErrorStateEkf)(config, calibration)
        f.add_imu(m.imu())
        f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
        out[s] = [f.update(int(t), regs[k], cov) for k, t in enumerate(times)]
    d = [np.abs(a.T_world_cam - b.T_world_cam).max() for a, b in zip(out[0.0], out[0.1])]
    assert d[5] > 1e-6  # inside the 0.1 s: different
    assert d[-1] < 0.2 * max(d[:20])  # long after it: the same registrations pull both to the same estimate


def test_the_startup_widening_is_on_by_default_for_half_a_second():
    # Session 33: on after the demos' recipes on other seeds gained (docs in FusionConfig.registration_startup_s).
    config = FusionConfig()
    assert config.registration_startup_s == 0.5 and config.registration_startup_inflation == 10.0
    from evpose.fusion.startup import startup_inflated

    C = _ridge_covariance()
    assert startup_inflated(config, 0, 499_999, C) is not C
    assert startup_inflated(config, 0, 500_000, C) is C
