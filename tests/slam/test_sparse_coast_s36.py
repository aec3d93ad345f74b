"""Coasting through a sparse scene: gaps between MCIs beyond ``TrackingConfig.coast_gap_cap_ms`` do not use up ``coast_s``."""

from evpose.slam.config import SlamConfig
from evpose.slam.sparse_coast import sparse_gap_excess_s


def test_dense_mcis_leave_nothing_out():
    traj = list(range(0, 200_001, 10_000))  # every 10 ms
    assert sparse_gap_excess_s(traj, 50_000, 210_000, 20.0) == 0.0


def test_each_gap_counts_up_to_the_cap():
    # Last visual MCI at 0, coasted MCIs 50 ms apart, the new MCI 40 ms after the last: 30 + 30 + 20 ms left out.
    traj = [0, 50_000, 100_000]
    assert abs(sparse_gap_excess_s(traj, 0, 140_000, 20.0) - 0.080) < 1e-12
    # Poses before the last visual MCI do not count.
    assert abs(sparse_gap_excess_s([-300_000, -100_000] + traj, 0, 140_000, 20.0) - 0.080) < 1e-12


def test_without_coasted_poses_the_gap_since_the_last_visual_mci_counts():
    assert abs(sparse_gap_excess_s([], 1_000_000, 1_100_000, 20.0) - 0.080) < 1e-12
    assert abs(sparse_gap_excess_s([0, 500_000], 1_000_000, 1_100_000, 20.0) - 0.080) < 1e-12


def test_off_by_default():
    assert SlamConfig().tracking.coast_gap_cap_ms == 0.0
    assert sparse_gap_excess_s([0, 500_000], 0, 1_000_000, 0.0) == 0.0
