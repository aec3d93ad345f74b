"""The ``fusion.snapshot_restore`` benchmark runs against gtsam's own fixed-lag smoother: our fusion must stay
comparable to it (it broke once when the fusion began forcing relinearisations that gtsam's smoother cannot make)."""

from evpose.bench import BenchContext
from evpose.bench.fusion import bench_snapshot_restore


def test_snapshot_restore_bench_matches_gtsams_smoother_and_restores_bit_for_bit(tmp_path):
    out = bench_snapshot_restore(BenchContext(quick=True, work_dir=tmp_path))
    assert out["estimates_identical_to_gtsam_smoother"] is True
    assert out["restored_runs_bit_identical"] is True
    assert out["updates"] == 620
