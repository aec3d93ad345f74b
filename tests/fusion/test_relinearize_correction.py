"""The factor graph relinearises its window at once after a large velocity correction (a start without velocity)."""

import numpy as np
import pytest

from evpose.errors import ConfigError
from evpose.fusion.config import FusionConfig
from evpose.fusion.factor_graph import FactorGraphFusion

from fusion_helpers import make_motion, noisy_registrations


def _run(calibration, threshold, with_velocity, updates):
    m = make_motion(duration_s=0.8, imu_rate_hz=500.0, acc_bias=(0.08, -0.05, 0.1), gyro_bias=(0.01, -0.02, 0.015),
                    accel_noise_density=2e-3, gyro_noise_density=1.7e-4, seed=0)
    f = FactorGraphFusion(FusionConfig(relinearize_correction_velocity=threshold), calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    v0 = m.camera_velocity([t0], calibration.T_cam_imu)[0] if with_velocity else None
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), v0)
    times = t0 + np.arange(5000, 5000 * (updates + 1), 5000)
    _, regs, cov = noisy_registrations(m, calibration.T_cam_imu, times, 0.002, np.radians(0.1), seed=1)
    return f, [f.update(int(t), regs[k], cov) for k, t in enumerate(times)]


def _linearised_velocity_gap(f) -> float:
    """|estimate - linearisation point| of the newest state's velocity, m/s."""
    key = f._keys(f.index)[1]
    lin = np.asarray(f.smoother.isam.getLinearizationPoint().atVector(key))
    return float(np.linalg.norm(np.asarray(f.smoother.calculateEstimateVector(key)) - lin))


def test_a_start_without_velocity_relinearises_the_corrected_states_at_once(calibration):
    on, _ = _run(calibration, 0.05, with_velocity=False, updates=3)
    off, _ = _run(calibration, 0.0, with_velocity=False, updates=3)
    # Without the trigger the third state is still linearised at its IMU prediction, m/s away from its estimate.
    assert _linearised_velocity_gap(off) > 0.1
    assert _linearised_velocity_gap(on) < 0.01


def test_forced_relinearisations_come_only_while_the_start_is_being_corrected(calibration, monkeypatch):
    forced = []
    joint = FactorGraphFusion._joint_optimisation

    def spy(self, force=False):
        if force:
            forced.append(self.n_updates)
        return joint(self, force)

    monkeypatch.setattr(FactorGraphFusion, "_joint_optimisation", spy)
    _run(calibration, 0.05, with_velocity=False, updates=100)
    assert forced and forced[0] == 1 and max(forced) < 20
    forced.clear()
    _run(calibration, 0.05, with_velocity=True, updates=100)
    assert max(forced, default=0) < 20  # tracking from a known velocity: at most while its 0.5 m/s prior settles


def test_a_negative_threshold_is_rejected():
    with pytest.raises(ConfigError):
        FactorGraphFusion(FusionConfig(relinearize_correction_velocity=-0.1))
