"""Engines: seeking lands on exactly the state an uninterrupted (headless) run reaches."""

import numpy as np

from app.engine import EventsOnlyEngine, EventsViewConfig, TrackerEngine
from evpose.tracker.session import TrackingSession


def test_events_only_seek_equals_uninterrupted_run(bar_recording):
    run = EventsOnlyEngine(bar_recording)
    frames = [run.step() for _ in range(40)]
    other = EventsOnlyEngine(bar_recording)
    for k in (30, 3, 39, 0):
        f = other.seek(frames[k].t_us)
        assert f.index == k
        assert np.array_equal(f.ts_positive, frames[k].ts_positive)
        assert np.array_equal(f.ts_negative, frames[k].ts_negative)
        assert np.array_equal(f.tdf, frames[k].tdf)
        assert len(other.history) == k + 1
        assert [s.counts["events_in"] for s in other.history] == [s.counts["events_in"] for s in run.history[: k + 1]]


def test_events_only_covers_the_whole_recording(bar_recording):
    eng = EventsOnlyEngine(bar_recording, EventsViewConfig(window_us=50_000))
    n = 0
    while eng.step() is not None:
        n += 1
    assert sum(s.counts["events_in"] for s in eng.history) == len(bar_recording.events)
    assert n == eng.n_steps


def test_tracker_engine_seek_matches_headless_session(squares_scene):
    rec, cmap = squares_scene
    headless = TrackingSession(rec, cmap)
    results = [headless.step() for _ in range(30)]
    eng = TrackerEngine(rec, cmap)
    for k in (25, 7, 29):
        f = eng.seek(results[k].t_us)
        assert f.index == k and f.t_us == results[k].t_us
        assert np.array_equal(f.pose, results[k].pose)
        assert f.tdf.shape == (rec.calibration.height, rec.calibration.width)
        assert f.projected_uv is not None and len(f.projected_uv) == len(f.residuals)
    f = eng.seek_step(eng.history[-1].index - 1)
    assert np.array_equal(f.pose, results[28].pose)


def test_prefetch_leaves_the_shown_step_unchanged_and_covers_the_recording(squares_scene):
    rec, cmap = squares_scene
    headless = TrackingSession(rec, cmap)
    results = headless.run()
    eng = TrackerEngine(rec, cmap)
    for _ in range(10):
        eng.step()
    while eng.prefetch(30):
        pass
    assert eng.session.step_count == 10 and len(eng.history) == 10
    f = eng.step()
    assert f.index == 10 and np.array_equal(f.pose, results[10].pose)
    snapshots = sorted(eng.session._snapshots)
    assert snapshots[-1] >= eng.session.total_steps - eng.config.snapshot_every
    f = eng.seek(results[-3].t_us)
    assert np.array_equal(f.pose, results[-3].pose)
    # Restored ahead of what this engine had stepped: the history is complete and equal to the headless run.
    assert len(eng.history) == len(results) - 2
    assert all(np.array_equal(h.pose, r.pose) for h, r in zip(eng.history, results))
