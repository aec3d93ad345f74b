"""The simulation cache returns exactly what a fresh simulation gives, and keys on the configuration."""

import numpy as np

from evpose.sim import SimulationConfig, simulate
from evpose.sim.cache import load_or_simulate, simulation_key
from evpose.sim.lidar import LidarConfig


def test_cache_hit_equals_a_fresh_simulation(tmp_path):
    cfg = SimulationConfig(scenario="landing", seconds=0.03, resolution=(48, 36), seed=4, lidar=LidarConfig(density_per_m2=2.0))
    first = load_or_simulate(cfg, tmp_path, stem="tiny")
    again = load_or_simulate(cfg, tmp_path, stem="tiny")
    fresh = simulate(cfg)
    assert again.files["recording"].exists() and again.recording.source is not None  # loaded from disk
    for r in (first, again):
        np.testing.assert_array_equal(r.recording.events.t, fresh.recording.events.t)
        np.testing.assert_array_equal(r.recording.events.p, fresh.recording.events.p)
        np.testing.assert_array_equal(r.recording.imu.gyro, fresh.recording.imu.gyro)
        np.testing.assert_array_equal(r.cloud_points, fresh.cloud_points)
        np.testing.assert_array_equal(r.imu_truth.acc_bias, fresh.imu_truth.acc_bias)


def test_cache_key_depends_on_the_configuration():
    a = SimulationConfig(scenario="landing", seconds=0.03, seed=1)
    assert simulation_key(a) == simulation_key(SimulationConfig(scenario="landing", seconds=0.03, seed=1))
    assert simulation_key(a) != simulation_key(SimulationConfig(scenario="landing", seconds=0.03, seed=2))
