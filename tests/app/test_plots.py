"""Plot series: bounded windows, pose errors against ground truth."""

import numpy as np

from app.frame import StepSummary
from app.plots import plot_series, pose_errors


def _history(gt, n, offset=0.0):
    out = []
    for i in range(n):
        T = gt.interpolate(gt.t[0] + i * 10_000).matrix(0)
        T[0, 3] += offset
        out.append(StepSummary(i, int(gt.t[0] + i * 10_000), T, None, "ok", {"registration": 1.0, "total": 2.0},
                               {"events_in": 100, "events_kept": 60, "inliers": 50, "points_used": 80}))
    return out


def test_pose_errors_are_zero_on_ground_truth_and_measure_offsets(bar_recording):
    gt = bar_recording.ground_truth
    pe, re = pose_errors(_history(gt, 20), gt)
    assert np.allclose(pe, 0, atol=1e-9) and np.allclose(re, 0, atol=1e-7)
    pe, _ = pose_errors(_history(gt, 20, offset=0.03), gt)
    assert np.allclose(pe, 0.03)


def test_series_cover_a_bounded_window_of_the_latest_steps(bar_recording):
    gt = bar_recording.ground_truth
    series = plot_series(_history(gt, 90), gt, window=25)
    assert set(series) == {"pose error", "latency per module [ms]", "events per second", "inliers", "share filtered"}
    for labels, data in series.values():
        assert len(data) == len(labels) + 1
        assert all(len(d) == 25 for d in data)
    assert series["latency per module [ms]"][0] == ("registration", "total")
    assert np.allclose(series["share filtered"][1][1], 40.0)
    assert np.allclose(series["events per second"][1][1], 100 / 0.01 / 1e3)


def test_the_first_steps_one_time_start_up_is_left_out_of_the_latency_plot(bar_recording):
    gt = bar_recording.ground_truth
    hist = _history(gt, 5)
    hist[0].timings_ms["total"] = 30_000.0  # the first step loading its compiled kernels
    (labels, data) = plot_series(hist, gt)["latency per module [ms]"]
    total = data[1 + labels.index("total")]
    assert np.isnan(total[0]) and np.allclose(total[1:], 2.0)
    later = plot_series(hist[1:], gt)["latency per module [ms]"][1]
    assert not np.isnan(later[1]).any()  # a window starting later keeps all its steps
