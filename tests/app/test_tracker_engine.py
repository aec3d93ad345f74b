"""Tracker engine: every frame it shows (live, kept by the run-ahead, after seeks) equals the headless run's step."""

import dataclasses

import numpy as np

from app.frame_cache import FrameCacheConfig, quantize
from app.tracker_engine import TrackerEngine, frame_from_result
from evpose.tracker.session import TrackingSession


def _headless(rec, cmap, debug_at=()):
    s = TrackingSession(rec, cmap)
    out = []
    while True:
        r = s.step(debug=len(out) in debug_at)
        if r is None:
            return out
        out.append(r)


def _same_frame(f, result):
    ref = frame_from_result(result, f.index)
    assert f.t_us == ref.t_us and f.status == ref.status
    assert np.array_equal(f.pose, ref.pose)
    for name in ("ts_positive", "ts_negative", "tdf"):
        assert np.array_equal(getattr(f, name), quantize(getattr(ref, name))), name
    for name in ("projected_uv", "residuals", "weights", "point_index", "visible_index", "predicted_polarity"):
        assert np.array_equal(getattr(f, name), getattr(ref, name), equal_nan=name in ("projected_uv",)), name
    assert np.array_equal(f.events_kept.t, ref.events_kept.t) and np.array_equal(f.events_removed.t, ref.events_removed.t)


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
    assert len(eng.history) == 29 and all(np.array_equal(h.pose, r.pose) for h, r in zip(eng.history, results))


def test_prefetch_leaves_the_shown_step_unchanged_and_keeps_grid_frames(squares_scene):
    rec, cmap = squares_scene
    every = 4
    results = _headless(rec, cmap, debug_at=range(0, 1000, every))
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=every * 5.0))
    assert eng.cache.every == every
    for _ in range(10):
        eng.step()
    while eng.prefetch(30):
        pass
    assert eng.frontier == eng.n_steps == len(results)
    assert eng.shown_index == 9 and len(eng.history) == 10
    f = eng.step()
    assert f.index == 10 and np.array_equal(f.pose, results[10].pose)
    # The run-ahead kept a frame on every grid step, each equal to the headless run's step there.
    assert all(k in eng.cache for k in range(0, len(results), every))
    for k in (0, every * 3, (len(results) - 1) // every * every):
        _same_frame(eng.cache.get(k), results[k])
    # It keeps a snapshot every 100 ms (for the shown session) and has never restored one.
    assert eng._ahead.snapshot_steps == list(range(0, eng.n_steps + 1, 20))


def test_seek_near_lands_on_the_kept_frame_at_or_before_the_target(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))  # every 5 steps
    eng.step()
    while eng.prefetch(50):
        pass
    k = 37
    f = eng.seek_near(results[k].t_us)
    assert f.index == 35 and np.array_equal(f.pose, results[35].pose)
    assert len(eng.history) == 36 and all(np.array_equal(h.pose, r.pose) for h, r in zip(eng.history, results))
    # Stepping on from a kept frame is exact: the step after it and the one before it.
    f = eng.step()
    assert f.index == 36 and np.array_equal(f.pose, results[36].pose)
    f = eng.seek_step(34)
    assert f.index == 34 and np.array_equal(f.pose, results[34].pose)


def test_seek_past_the_run_ahead_steps_there_and_keeps_the_grid_frame(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))
    eng.step()
    eng.prefetch(10)
    f = eng.seek_near(results[62].t_us)
    assert f.index == 60 and np.array_equal(f.pose, results[60].pose)
    assert 60 in eng.cache
    assert [s.index for s in eng.history] == list(range(61))


def test_playback_strides_show_kept_frames_with_a_complete_history(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))
    eng.step()
    shown = []
    while (f := eng.play_step(7)) is not None:
        shown.append(f.index)
        assert np.array_equal(f.pose, results[f.index].pose)
        if len(shown) == 3:
            while eng.prefetch(50):  # from here on, frames come from the cache
                pass
    assert shown[0] == 5 and all(0 < b - a <= 7 for a, b in zip(shown, shown[1:]))
    assert shown[-1] == len(results) - 1
    assert all(np.array_equal(h.pose, r.pose) for h, r in zip(eng.history, results))
    traj = eng.trajectory()
    assert len(traj) > 0 and traj.t[-1] == results[-1].t_us


def test_a_tiny_budget_keeps_the_frames_nearest_the_shown_step(squares_scene):
    rec, cmap = squares_scene
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=5.0, budget_mb=1.0))
    eng.step()
    while eng.prefetch(50):
        pass
    assert 0 < eng.cache.nbytes <= eng.cache.budget + max(1, eng.cache.nbytes // max(len(eng.cache), 1))
    assert len(eng.cache) < eng.n_steps and eng.cache.evicted > 0
    assert 0 in eng.cache or 1 in eng.cache  # the shown step is 0: the frames kept are the nearest to it


def test_a_jump_past_the_run_ahead_is_made_by_the_run_ahead_and_kept(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=5.0))  # every step kept
    eng.step()
    eng.prefetch(5)
    f = eng.seek(results[70].t_us)
    assert f.index == 70 and eng.frontier == 71
    assert all(k in eng.cache for k in range(71))  # every step on the way can now be shown at once
    f = eng.seek(results[33].t_us)
    assert f.index == 33 and np.array_equal(f.pose, results[33].pose) and eng.session.step_count <= 1


def test_the_run_ahead_started_late_does_not_hold_back_the_shown_session(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap)
    f = eng.seek(results[40].t_us)  # no run-ahead yet: the shown session steps there
    eng.prefetch(3)  # the run-ahead starts at step 0, far behind
    f = eng.step()
    assert f.index == 41 and np.array_equal(f.pose, results[41].pose) and eng.frontier == 3


def test_the_run_ahead_computes_debug_products_only_on_the_frame_grid(squares_scene):
    rec, cmap = squares_scene
    eng = TrackerEngine(rec, cmap)  # default grid: 20 ms, every 4th step at 200 Hz
    assert eng.cache.every == 4
    debug_steps = _spy_debug(eng)
    while eng.prefetch(50):
        pass
    assert debug_steps == list(range(0, eng.n_steps, 4))
    assert sorted(eng.cache._frames) == debug_steps and len(eng._summaries) == eng.n_steps


def test_exact_steps_off_the_grid_restore_a_snapshot_the_run_ahead_left(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))
    eng.step()
    while eng.prefetch(50):
        pass
    assert 40 in eng._ahead.snapshot_steps and 40 not in eng.session.snapshot_steps
    f = eng.seek_step(57)  # off the grid: replayed from the run-ahead's snapshot at 40, not from step 1
    assert f.index == 57 and eng.session.step_count == 58 and 40 in eng.session.snapshot_steps
    _same_frame(f, _headless(rec, cmap, debug_at=(57,))[57])
    f = eng.seek_step(56)  # and back: the same snapshot again
    assert f.index == 56 and np.array_equal(f.pose, results[56].pose) and eng.session.step_count == 57
    f = eng.step()
    assert f.index == 57 and np.array_equal(f.pose, results[57].pose)


def test_a_stride_shorter_than_the_grid_plays_the_next_kept_frame(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))  # every 5 steps
    eng.step()
    while eng.prefetch(50):
        pass
    shown = [eng.play_step(2).index for _ in range(4)]
    assert shown == [5, 10, 15, 20]
    assert all(np.array_equal(eng.history[k].pose, results[k].pose) for k in range(21))
    eng2 = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))  # no run-ahead: grid steps are computed
    eng2.step()
    assert [eng2.play_step(2).index for _ in range(2)] == [5, 10] and 5 in eng2.cache


def test_the_run_ahead_thins_its_snapshots_to_their_budget_and_steps_stay_exact(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap)
    probe = TrackerEngine(rec, cmap, cache=FrameCacheConfig(snapshot_every_ms=50.0))
    probe.prefetch(10)
    one = probe._snapshot_bytes
    assert one > 0
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0, snapshot_every_ms=50.0, snapshot_budget_mb=3.5 * one / 2**20))
    eng.step()
    while eng.prefetch(50):
        pass
    kept = eng._ahead.snapshot_steps
    assert len(kept) * one <= 3.5 * one and kept[0] == 0
    assert eng._snapshot_spacing > 10 and all(k % eng._snapshot_spacing == 0 for k in kept)
    for k in (kept[-1] + 3, 13):
        f = eng.seek_step(k)
        assert f.index == k and np.array_equal(f.pose, results[k].pose)


def _spy_debug(eng):
    """The run-ahead of ``eng`` (made now), recording the step counts at which it computed debug products."""
    ahead = eng._new_session()
    debug_steps = []
    step = ahead.step

    def spy(debug=False):
        if debug:
            debug_steps.append(ahead.step_count)
        return step(debug=debug)

    ahead.step = spy
    eng._ahead = ahead
    return debug_steps


def test_a_catch_up_steps_plainly_to_a_far_seek_and_shows_the_headless_step(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap, debug_at=(80,))
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))  # every 5 steps
    debug_steps = _spy_debug(eng)
    eng.step()
    eng.prefetch(3)
    t = results[83].t_us
    assert eng.frontier == 4 and eng.catch_up_steps(t) == 76 and eng.catch_up_steps(t, exact=True) == 79
    assert eng.catch_up_progress(t)[1] == (results[80].t_us - rec.t_start_us) / 1e6
    slices = 1
    while not eng.catch_up(t, 7):
        slices += 1
    assert slices == 11 and eng.frontier == 80 and eng.catch_up_steps(t) == 0
    # No debug products, no kept frames on the way; only the run-ahead's snapshots and the summaries.
    assert debug_steps == [0] and sorted(eng.cache._frames) == [0]
    assert sorted(eng._unkept) == list(range(5, 80, 5)) and eng._ahead.snapshot_steps == list(range(0, 81, 20))
    f = eng.seek_near(t)
    assert f.index == 80 and debug_steps == [0, 80]
    _same_frame(f, results[80])
    assert [s.index for s in eng.history] == list(range(81))
    assert all(np.array_equal(h.pose, r.pose) and h.status == r.status.value for h, r in zip(eng.history, results))


def test_an_exact_catch_up_lands_on_the_step_off_the_grid(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap, debug_at=(83,))
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))
    eng.step()
    while not eng.catch_up(results[83].t_us, 50, exact=True):
        pass
    assert eng.frontier == 83
    f = eng.seek(results[83].t_us)
    assert f.index == 83
    _same_frame(f, results[83])


def test_the_grid_frames_a_catch_up_skipped_are_filled_in_after_the_run_ahead(squares_scene):
    rec, cmap = squares_scene
    results = _headless(rec, cmap, debug_at=range(0, 1000, 5))
    eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=25.0))
    eng.step()
    while not eng.catch_up(results[62].t_us, 50):
        pass
    eng.seek_near(results[62].t_us)
    assert eng._unkept and 30 not in eng.cache
    # Seeks into the gap are exact before it is filled (a restore of the run-ahead's snapshot and a few steps).
    f = eng.seek_near(results[33].t_us)
    assert f.index == 30
    _same_frame(f, results[30])
    while eng.prefetch(7):
        pass
    assert not eng._unkept and eng.frontier == eng.n_steps
    assert sorted(eng.cache._frames) == list(range(0, eng.n_steps, 5))
    for k in (5, 25, 55):
        _same_frame(eng.cache.get(k), results[k])
    assert eng.shown_index == 30


def test_a_seek_after_a_long_event_gap_lands_on_the_update_at_or_before_it(squares_scene):
    # The updates after a gap are no longer t0 + k * dt: seeking there used to land on the recording's last update.
    rec, cmap = squares_scene
    ev, gt, imu = rec.events, rec.ground_truth, rec.imu
    at, gap = int(ev.t[0]) + 100_000, 60_000_000
    later = lambda t: np.where(t >= at, t + gap, t)  # noqa: E731
    paused = dataclasses.replace(rec, events=type(ev)(later(ev.t), ev.x, ev.y, ev.p), imu=type(imu)(later(imu.t), imu.acc, imu.gyro),
                                 ground_truth=type(gt)(later(gt.t), gt.position, gt.quat_xyzw))
    results = _headless(paused, cmap)
    eng = TrackerEngine(paused, cmap)
    k = next(i for i, r in enumerate(results) if r.t_us > at + gap) + 3
    for t_us, want in ((results[k].t_us, k), (results[k].t_us + 1, k), (at + gap // 2, k - 4)):
        f = eng.seek(t_us)
        assert f.index == want and f.t_us == results[want].t_us
    assert eng.catch_up_progress(results[k].t_us, exact=True)[1] == (results[k].t_us - eng.t_start_us) / 1e6
    assert eng.seconds_of_steps(eng.n_steps) == (results[-1].t_us - eng.session.time_of(0)) / 1e6 > gap / 1e6


def test_stepping_forward_and_back_goes_through_the_update_that_stands_for_a_long_event_gap(squares_scene):
    # That update makes no images: it had no frame, so "forward >" at the last step before a 60 s gap did nothing
    # (the player redrew that step) and "< back" from the step after it likewise.
    from evpose.core.events import EventArray
    from evpose.core.imu import ImuSamples
    from evpose.core.trajectory import Trajectory

    rec, cmap = squares_scene
    cut, gap = rec.t_start_us + 250_000, 3_000_000
    shift = lambda t: np.where(t >= cut, t + gap, t)
    ev, gt, imu = rec.events, rec.ground_truth, rec.imu
    rec = dataclasses.replace(rec, events=EventArray(shift(ev.t), ev.x, ev.y, ev.p),
                              ground_truth=Trajectory(shift(gt.t), gt.position, gt.quat_xyzw),
                              imu=ImuSamples(shift(imu.t), imu.acc, imu.gyro), source=None)
    eng = TrackerEngine(rec, cmap)
    before = eng.seek(cut - 1)
    k = before.index
    while eng.session.schedule.gap_of(k + 2) is None:  # to the last step before the gap
        k += 1
    stand = eng.seek_step(k + 1)
    assert stand is not None and stand.index == k + 1 and stand.status == "lost" and "track is lost over the gap" in stand.reason
    assert stand.tdf.shape == before.tdf.shape
    after = eng.step()
    assert after.index == k + 2 and after.t_us > cut + gap
    assert eng.seek_step(k + 1).index == k + 1 and eng.seek_step(k).index == k  # and back again
