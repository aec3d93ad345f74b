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


def test_a_miss_returns_exactly_what_later_hits_return(tmp_path):
    # 100 kHz ground truth: with 3001 poses some quaternions move by 1 ulp when the HDF5 reader re-normalises them,
    # which the in-memory result of a miss used to keep (a benchmark's first run then differed from its reruns).
    cfg = SimulationConfig(scenario="landing", seconds=0.03, resolution=(48, 36), seed=4, gt_rate_hz=100_000, lidar=LidarConfig(density_per_m2=2.0))
    miss = load_or_simulate(cfg, tmp_path)
    hit = load_or_simulate(cfg, tmp_path)
    for name in ("t", "position", "quat_xyzw"):
        np.testing.assert_array_equal(getattr(miss.recording.ground_truth, name), getattr(hit.recording.ground_truth, name))
    for name in ("t", "x", "y", "p"):
        np.testing.assert_array_equal(getattr(miss.recording.events, name), getattr(hit.recording.events, name))
    np.testing.assert_array_equal(miss.recording.imu.acc, hit.recording.imu.acc)
    np.testing.assert_array_equal(miss.cloud_points, hit.cloud_points)
    assert miss.files == hit.files


def test_scenario_key_changes_with_the_simulator_source(monkeypatch):
    from evpose.eval.scenarios import ScenarioSpec
    from evpose.sim import cache

    spec = ScenarioSpec(scenario="landing", seconds=0.5, seed=2)
    before = spec.key()
    assert before == ScenarioSpec(scenario="landing", seconds=0.5, seed=2).key()
    monkeypatch.setattr(cache, "source_digest", lambda *folders: "edited simulator")
    assert spec.key() != before


def test_source_digest_follows_every_python_file_of_the_folders(tmp_path):
    from evpose.sim.cache import source_digest

    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "notes.txt").write_text("ignored")
    first = source_digest(tmp_path)
    (tmp_path / "notes.txt").write_text("still ignored")
    assert source_digest(tmp_path) == first
    (tmp_path / "a.py").write_text("x = 2\n")
    assert source_digest(tmp_path) != first
