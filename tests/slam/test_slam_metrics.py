"""Tests of evpose/eval/slam_metrics.py (kept with the SLAM tests, whose area owns the module)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.eval.slam_metrics import atlas_metrics, status_durations_s


def _gt():
    t = np.arange(0, 2_000_001, 10_000, dtype=np.int64)
    a = t / 1e6  # 1 m/s along a circle of radius 1 m (a straight line would make Umeyama degenerate)
    pos = np.c_[np.cos(a), np.sin(a), 0.1 * a]
    return Trajectory.from_arrays(t, pos, Rotation.from_rotvec(np.c_[0 * a, 0 * a, a]).as_quat())


def _scaled_piece(gt, t0, t1, scale, offset):
    piece = gt.time_window(t0, t1)
    return Trajectory.from_arrays(piece.t, piece.position * scale + offset, piece.quat_xyzw)


def test_scale_aligned_maps_have_zero_error_and_paper_stability():
    gt = _gt()
    maps = [_scaled_piece(gt, 0, 800_000, 0.3, [5, 1, 0]), _scaled_piece(gt, 1_000_000, 1_900_000, 2.0, [0, 0, 3])]
    m = atlas_metrics(maps, gt, correct_scale=True)
    assert len(m.maps) == 2
    assert m.rpe_trans_per_m < 1e-9 and m.rpe_rot_deg_per_m < 1e-6 and m.ate_percent < 1e-6
    assert m.maps[0].scale == pytest.approx(1 / 0.3)
    speed = np.sqrt(1 + 0.01)
    assert m.tracked_time_s == pytest.approx(0.79 + 0.89)
    assert m.distance_m == pytest.approx((0.79 + 0.89) * speed, rel=1e-4)
    assert m.stability == pytest.approx((0.79 + 0.89) ** 2 * speed, rel=1e-4)
    assert m.tracked_fraction == pytest.approx((0.79 + 0.89) / 2.0)


def test_rpe_is_normalised_by_travelled_distance_and_averaged_over_maps():
    gt = _gt()
    rng = np.random.default_rng(0)
    a = gt.time_window(0, 500_001)
    noisy = Trajectory.from_arrays(a.t, a.position + rng.normal(0, 0.01, a.position.shape), a.quat_xyzw)
    m = atlas_metrics([noisy], gt, correct_scale=False)
    mm = m.maps[0]
    assert m.rpe_trans_per_m == pytest.approx(mm.rpe_trans_m / mm.distance_m)
    assert 0.005 < mm.rpe_trans_m < 0.03
    assert mm.distance_m == pytest.approx(0.5 * np.sqrt(1.01), rel=1e-4)


def test_short_maps_are_ignored_and_missing_ground_truth_is_an_input_error():
    gt = _gt()
    assert atlas_metrics([gt[:2]], gt, correct_scale=True).maps == []
    with pytest.raises(InputError):
        atlas_metrics([gt], gt[:1], correct_scale=True)


def test_scale_drift_is_zero_for_a_uniformly_scaled_map_and_measures_a_scale_change():
    gt = _gt()
    uniform = atlas_metrics([_scaled_piece(gt, 0, 2_000_001, 0.25, [1, 2, 3])], gt, correct_scale=True).maps[0]
    assert uniform.segment_scales == pytest.approx([4.0] * 4, rel=1e-6)
    assert uniform.scale_drift_percent == pytest.approx(0.0, abs=1e-6)
    # The map's second second is drawn 1.5x larger than its first (scale drift of a monocular map).
    t, p = gt.t, gt.position.copy()
    late = t >= 1_000_000
    p[late] = p[late][0] + 1.5 * (p[late] - p[late][0]) + (p[late][0] - p[~late][-1]) * 0.5
    drifting = Trajectory.from_arrays(t, p, gt.quat_xyzw)
    m = atlas_metrics([drifting], gt, correct_scale=True, duration_s=2.0)
    assert m.maps[0].scale_drift_percent == pytest.approx(50.0, rel=0.02)
    assert m.to_dict()["scale_drift_percent_max"] == pytest.approx(50.0, rel=0.02)


def test_scale_drift_of_a_map_shorter_than_two_segments_is_null_so_summaries_compare_equal():
    gt = _gt()
    short = atlas_metrics([_scaled_piece(gt, 0, 400_000, 2.0, [0, 0, 0])], gt, correct_scale=True).to_dict()
    assert short["scale_drift_percent_max"] is None and short["per_map"][0]["scale_drift_percent"] is None
    assert short == atlas_metrics([_scaled_piece(gt, 0, 400_000, 2.0, [0, 0, 0])], gt, correct_scale=True).to_dict()


def test_spread_summary_reports_mean_median_extremes_and_runs_within_target():
    from evpose.eval.slam_metrics import spread_summary

    s = spread_summary([1.5, 4.0, 2.0, float("nan"), 10.5], target=2.0)
    assert s == {"runs": 4, "mean": 4.5, "median": 3.0, "best": 1.5, "worst": 10.5, "within_target": 2}
    assert spread_summary([], target=2.0)["runs"] == 0


def test_each_mci_status_owns_the_time_since_the_previous_mci():
    t = np.array([100_000, 300_000, 600_000, 700_000])
    d = status_durations_s(t, ["not_initialised", "ok", "coasting", "ok"], 0, 1_000_000)
    assert d == pytest.approx({"not_initialised": 0.1, "ok": 0.3, "coasting": 0.3, "none": 0.3})
    assert sum(d.values()) == pytest.approx(1.0)
    assert status_durations_s(np.zeros(0, np.int64), [], 0, 500_000) == pytest.approx({"none": 0.5})


def test_status_durations_reject_unsorted_or_mismatched_inputs():
    with pytest.raises(ValueError, match="sorted"):
        status_durations_s(np.array([2, 1]), ["ok", "ok"], 0, 3)
    with pytest.raises(ValueError, match="statuses"):
        status_durations_s(np.array([1, 2]), ["ok"], 0, 3)
