"""Plot series: bounded windows, pose errors against ground truth (SLAM: after each map's alignment), reasons for empty plots."""

import dataclasses

import numpy as np

from app.frame import StepSummary
from app.plots import MIN_X_SPAN_S, SLAM_POSE_ERROR, WINDOW_STEPS, PlotsView, empty_reasons, plot_series, pose_errors, x_range, y_range


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


def _in_map_frame(history, sim3):
    """The steps' poses as a SLAM map with its own frame and scale would hold them (the inverse of ``sim3``)."""
    out = []
    for s in history:
        T = np.eye(4)
        T[:3, :3] = sim3.R.T @ s.pose[:3, :3]
        T[:3, 3] = sim3.R.T @ (s.pose[:3, 3] - sim3.t) / sim3.s
        out.append(StepSummary(s.index, s.t_us, T, None, "ok", {}, {**s.counts, "map_id": 0}))
    return out


def test_slam_pose_errors_are_measured_after_each_maps_alignment_and_unknown_without_one(bar_recording):
    from scipy.spatial.transform import Rotation

    from evpose.eval.sim3_alignment import Sim3

    gt = bar_recording.ground_truth
    sim3 = Sim3(Rotation.from_euler("xyz", [0.3, -0.2, 1.0]).as_matrix(), np.array([1.0, -2.0, 0.5]), 0.25)
    hist = _in_map_frame(_history(gt, 20), sim3)
    pe, re = pose_errors(hist, gt, {0: sim3})
    assert np.allclose(pe, 0, atol=1e-9) and np.allclose(re, 0, atol=1e-7)
    assert np.isnan(pose_errors(hist, gt, {1: sim3})[0]).all()  # map 0 has no alignment yet
    assert np.nanmax(pose_errors(hist, gt)[0]) > 0.5  # compared in the map's own frame, the error is meaningless
    series = plot_series(hist, gt, alignments={0: sim3})
    assert SLAM_POSE_ERROR in series and "pose error" not in series and "tracks and map points" in series


def test_empty_plots_say_why_in_events_only_view_without_ground_truth_and_before_slam_aligns(bar_recording):
    gt = bar_recording.ground_truth
    events_only = [StepSummary(i, int(gt.t[0] + i * 10_000), None, None, "events only", {"total": 1.0},
                               {"events_in": 100, "events_kept": 100}) for i in range(10)]
    note = "No contour map selected: showing events and time surfaces only."
    why = empty_reasons(plot_series(events_only, gt), events_only, gt, note)
    assert set(why) == {"pose error", "inliers"} and note in why["pose error"] and "no registration" in why["inliers"]
    for s in events_only[:-1]:  # a seek's skipped steps are not timed
        s.timings_ms.clear()
    assert "not timed" in empty_reasons(plot_series(events_only, gt), events_only, gt, note)["latency per module [ms]"]
    # Step 1 after opening: the first step's timing is left out, no seek went past anything.
    first_two = [StepSummary(i, int(gt.t[0] + i * 10_000), None, None, "events only", {"total": 1.0}, {"events_in": 100})
                 for i in range(2)]
    why = empty_reasons(plot_series(first_two, gt), first_two, gt, note)["latency per module [ms]"]
    assert "one step timed so far" in why and "seek" not in why
    tracked = _history(gt, 10)
    assert empty_reasons(plot_series(tracked, gt), tracked, gt) == {}
    assert "no ground truth" in empty_reasons(plot_series(tracked, None), tracked, None)["pose error"]
    slam = [StepSummary(i, s.t_us, s.pose, None, "ok", {}, {"map_id": 0, "tracks": 50, "map_points": 20, "events_in": 100, "events_kept": 100})
            for i, s in enumerate(tracked)]
    why = empty_reasons(plot_series(slam, gt, alignments={}), slam, gt)
    assert list(why) == [SLAM_POSE_ERROR] and "aligned" in why[SLAM_POSE_ERROR]


class _Handle:
    def __init__(self, content=None, data=None):
        self.content, self.data, self.visible, self.removed = content, data, True, False

    def remove(self):
        self.removed = True


class _Gui:
    def __init__(self):
        self.added = []

    def add_markdown(self, content, order=None):
        self.added.append(("markdown", order, _Handle(content=content)))
        return self.added[-1][2]

    def add_uplot(self, data, series, order=None, **kwargs):
        self.added.append((kwargs["title"], order, _Handle(data=data)))
        self.added[-1][2].scales = kwargs["scales"]
        return self.added[-1][2]


def test_a_plot_with_nothing_to_draw_is_replaced_in_place_by_its_reason_and_comes_back_with_data(bar_recording):
    gt = bar_recording.ground_truth
    gui = _Gui()
    view = PlotsView(gui)
    view.update(_history(gt, 10), gt)
    pose_plot, order = next((h, o) for kind, o, h in gui.added if kind == "pose error")
    assert pose_plot.visible and not view.notes
    lost = [StepSummary(s.index, s.t_us, None, None, "lost", s.timings_ms, s.counts) for s in _history(gt, 10)]
    view.update(lost, gt)
    note = view.notes["pose error"]
    assert not pose_plot.visible and note.visible and "tracker is lost" in note.content
    assert next(o for kind, o, h in gui.added if h is note) == order  # the reason takes the plot's place
    view.update(_history(gt, 10, offset=0.03), gt)
    assert pose_plot.visible and not note.visible and np.allclose(pose_plot.data[1], 3.0)
    assert np.allclose(pose_plot.scales["y"]["range"], (0.0, 4.4))  # 3 cm: 10 % over a round 4, set here (see y_range)

def test_plots_are_hidden_not_removed_when_a_recording_opens_and_reused_after(bar_recording):
    # viser's browser code applies a batch's updates after its removals: plots removed at a recording switch while
    # playing got the updates sent just before ("Tried to update non-existent component" in the console).
    gt = bar_recording.ground_truth
    gui = _Gui()
    view = PlotsView(gui)
    view.update(_history(gt, 10), gt)
    lost = [StepSummary(s.index, s.t_us, None, None, "lost", s.timings_ms, s.counts) for s in _history(gt, 10)]
    view.update(lost, gt)
    made = [h for _, _, h in gui.added]
    view.clear()
    assert not any(h.removed or h.visible for h in made)
    view.update(_history(gt, 10), gt)
    assert [h for _, _, h in gui.added] == made  # the same plots shown again
    assert view.handles["pose error"][1].visible and not view.notes["pose error"].visible
    changed = [StepSummary(s.index, s.t_us, s.pose, None, "ok", {"other module": 1.0}, s.counts) for s in _history(gt, 10)]
    latency = view.handles["latency per module [ms]"][1]
    view.update(changed, gt)  # other series: another plot in its place, the first hidden, not removed
    assert not latency.visible and not latency.removed and view.handles["latency per module [ms]"][1].visible
    view.update(_history(gt, 10), gt)
    assert view.handles["latency per module [ms]"][1] is latency and latency.visible
    assert not any(h.removed for _, _, h in gui.added)


def test_y_ranges_are_round_cover_every_value_and_ignore_the_nans_uplot_could_not_range():
    assert np.allclose(y_range((np.array([np.nan, 0.2, 1.9]), np.array([np.nan, np.nan, 0.5]))), (0.0, 2.2))
    assert np.allclose(y_range((np.array([np.nan, 120.0, 230.0]),)), (0.0, 275.0))
    assert np.allclose(y_range((np.array([101.0]),)), (0.0, 132.0))  # 1.2 x 100 x 1.1
    assert np.allclose(y_range((np.array([np.nan, np.nan]),)), (0.0, 1.1))
    lo, hi = y_range((np.array([-3.0, 7.0]),))
    assert lo == -3.0 and hi >= 7.0


def test_every_plot_is_sent_the_x_range_of_its_latest_window(bar_recording):
    # Left to viser's client, the x bounds drifted after a seek then play: at 3.99 s the axis showed 1.0-1.9 s.
    gt = bar_recording.ground_truth
    gui = _Gui()
    view = PlotsView(gui)
    h = _history(gt, WINDOW_STEPS + 50)
    view.update(h[:20], gt)
    view.update(h, gt)
    t = np.array([s.t_us for s in h[-WINDOW_STEPS:]]) / 1e6
    plots = [hd for kind, _, hd in gui.added if kind != "markdown" and not hd.removed]
    assert plots and all(np.allclose(p.scales["x"]["range"], (t[0], t[-1])) for p in plots)
    assert x_range(np.array([0.035])) == (0.035, 0.035 + MIN_X_SPAN_S)  # one step: ticks that differ


def test_the_plots_start_afresh_after_a_gap_the_steps_skip(bar_recording):
    # Drawn across a 60 s event gap, the steps after it were squeezed into the right edge of a 60 s time axis and
    # joined to those before by a straight line through the gap.
    gt = bar_recording.ground_truth
    h = _history(gt, 30)
    after = [dataclasses.replace(s, index=s.index + 30, t_us=s.t_us + 60_000_000) for s in _history(gt, 5)]
    t = plot_series(h + after, gt)["events per second"][1][0]
    assert len(t) == 5 and t[0] >= 60.0
    assert len(plot_series(h, gt)["events per second"][1][0]) == 30
