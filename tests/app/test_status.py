"""Status line: says how far the run-ahead is, and nothing about it for engines without one."""

from types import SimpleNamespace

import numpy as np

from app.engine import Engine, EventsOnlyEngine
from app.frame import Frame
from app.status import run_ahead_note, status_markdown
from evpose.core.events import EventArray


def test_run_ahead_note_reports_progress_and_completion():
    eng = SimpleNamespace(n_steps=2000, frontier=840, step_us=5000)
    assert run_ahead_note(eng).startswith("run-ahead: 4.20 of 10.00 s ready")
    eng.frontier = 2000
    assert "done" in run_ahead_note(eng)


def test_events_only_status_has_no_run_ahead_note(bar_recording):
    eng = EventsOnlyEngine(bar_recording)
    z = np.zeros((2, 2), np.float32)
    f = Frame(3, 15_000, z, z, z, EventArray.empty(), EventArray.empty())
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0, "real_time_factor": 0.5})
    assert "step 3" in text and "real-time factor 0.50" in text and "run-ahead" not in text
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0, "real_time_factor": 0.0})  # nothing played yet
    assert "paused at 1.0x" in text and "real-time factor" not in text


def test_run_ahead_note_says_what_came_from_the_disk_cache_and_why_it_stopped_writing():
    disk = SimpleNamespace(error="")
    eng = SimpleNamespace(n_steps=2000, frontier=100, step_us=5000, ready_steps=2000, disk_steps=2000, disk=disk)
    note = run_ahead_note(eng)
    assert note.startswith("run-ahead done: all 10.00 s ready") and "10.00 s read from the disk cache" in note and "at 0.50 s" in note
    disk.error = "disk cache off: no space left"
    eng.ready_steps = eng.disk_steps = 400
    note = run_ahead_note(eng)
    assert note.startswith("run-ahead: 2.00 of 10.00 s ready (computing") and "no space left" in note


def test_a_far_seek_being_computed_shows_its_progress(bar_recording):
    eng = EventsOnlyEngine(bar_recording)
    z = np.zeros((2, 2), np.float32)
    f = Frame(3, 15_000, z, z, z, EventArray.empty(), EventArray.empty())
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0, "catching_up": (4.2, 9.0)})
    assert "computing 4.2 / 9.0 s" in text and "cancel" in text and "tracking is causal" in text
    assert "computing" not in status_markdown(f, eng, {"state": "paused", "catching_up": None})
    slam = Frame(3, 15_000, z, z, z, EventArray.empty(), EventArray.empty(), slam=SimpleNamespace())
    text = status_markdown(slam, eng, {"state": "paused", "speed": 1.0, "catching_up": (4.2, 9.0)})
    assert "SLAM is causal" in text and "tracking" not in text  # it said "tracking is causal" in SLAM mode


def test_run_ahead_note_says_frames_a_far_seek_skipped_are_being_filled_in():
    eng = SimpleNamespace(n_steps=2000, frontier=2000, step_us=5000, backfill_left=470)
    assert "filling in 470 frames a far seek skipped" in run_ahead_note(eng)
    eng.frontier = 1950
    assert run_ahead_note(eng).startswith("run-ahead: ") and "470 frames" in run_ahead_note(eng)
    eng.frontier, eng.backfill_left = 2000, 0
    assert "done" in run_ahead_note(eng)


def _demo_engine():
    """A stand-in for the landing demo's engine, with the engines' own last-step rule."""
    eng = SimpleNamespace(n_steps=793, t_end_us=3_999_995)
    eng.is_last = lambda frame: Engine.is_last(eng, frame)
    return eng


def _blank_frame(index, t_us):
    z = np.zeros((2, 2), np.float32)
    return Frame(index, t_us, z, z, z, EventArray.empty(), EventArray.empty())


def test_the_last_step_says_it_is_the_end_even_before_the_last_event():
    # The tracker's last step lies up to a step before the last event (landing demo: 3.995 of 3.999995 s).
    eng = _demo_engine()
    last = _blank_frame(792, 3_995_000)
    assert "the end of the recording" in status_markdown(last, eng, {"state": "paused", "speed": 1.0})
    assert "end of the recording" not in status_markdown(last, eng, {"state": "playing", "speed": 1.0})
    before = _blank_frame(791, 3_990_000)
    assert "end of the recording" not in status_markdown(before, eng, {"state": "paused", "speed": 1.0})


def test_the_first_step_says_nothing_comes_before_it_when_paused():
    # "< back" at step 0 did nothing without a word (the last step already said it was the end).
    eng = _demo_engine()
    first = _blank_frame(0, 35_000)
    assert "the first step of the recording" in status_markdown(first, eng, {"state": "paused", "speed": 1.0})
    assert "first step of the recording" not in status_markdown(first, eng, {"state": "playing", "speed": 1.0})
    second = _blank_frame(1, 40_000)
    assert "first step of the recording" not in status_markdown(second, eng, {"state": "paused", "speed": 1.0})


def _tracker_like(registered_flags, t0_us=1_000_000, step_us=5_000):
    hist = [SimpleNamespace(t_us=t0_us + k * step_us, counts={"registered": int(r)}) for k, r in enumerate(registered_flags)]
    return SimpleNamespace(contour_map=object(), history=hist, session=SimpleNamespace(t0_us=t0_us), t_start_us=0,
                           is_last=lambda frame: False)


def test_a_map_nothing_registers_against_for_a_second_is_flagged_as_possibly_the_wrong_one():
    z = np.zeros((2, 2), np.float32)
    f = Frame(200, 2_000_000, z, z, z, EventArray.empty(), EventArray.empty(), status="degraded", reason="only 21 of 712 map points")
    eng = _tracker_like([False] * 201)
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0})
    assert "no update has registered against this map in the first 1.00 s" in text and "this recording's map" in text
    assert "registered against this map" not in status_markdown(f, _tracker_like([False] * 150), {"state": "paused"})
    assert "registered against this map" not in status_markdown(f, _tracker_like([False] * 100 + [True] + [False] * 200), {})
    no_map = _tracker_like([False] * 300)
    no_map.contour_map = None  # the events-only view has no map to blame
    assert "registered against this map" not in status_markdown(f, no_map, {})


def test_a_map_registering_no_better_than_chance_for_a_second_is_flagged_too():
    z = np.zeros((2, 2), np.float32)
    f = Frame(200, 2_000_000, z, z, z, EventArray.empty(), EventArray.empty(), status="ok")

    def counts(inliers, hits):  # 500 points in view; hits of 800 displaced samples
        return {"registered": 1, "inliers": inliers, "points_in_image": 500, "chance_hits": hits, "chance_samples": 800}

    eng = _tracker_like([True] * 201)
    for h in eng.history:  # dense events: 60 % inliers where 60 % of the displaced samples land on events too
        h.counts = counts(300, 480)
    text = status_markdown(f, eng, {"state": "paused", "speed": 1.0})
    assert "hardly more often than chance in the first second" in text and "this recording's map" in text
    for h in eng.history:  # a right map: 40 % inliers where 10 % would land by chance
        h.counts = counts(200, 80)
    assert "than chance" not in status_markdown(f, eng, {"state": "paused", "speed": 1.0})


def test_the_reason_follows_the_status_without_nesting_its_own_parentheses():
    z = np.zeros((2, 2), np.float32)
    f = Frame(159, 800_000, z, z, z, EventArray.empty(), EventArray.empty(), status="ok",
              reason="40 inliers (2 re-found by projection), rms 1.30 px")
    text = status_markdown(f, SimpleNamespace(is_last=lambda frame: False), {"state": "paused", "speed": 1.0})
    assert "**ok** \u2014 40 inliers (2 re-found by projection), rms 1.30 px" in text and "((" not in text and "))" not in text
    ended = Frame(159, 800_000, z, z, z, EventArray.empty(), EventArray.empty(), status="lost",
                  reason="the IMU samples end at t=0.5 s: the fused modes track no further (--mode stpe needs no IMU)")
    text = status_markdown(ended, SimpleNamespace(is_last=lambda frame: False), {"state": "paused", "speed": 1.0})
    assert "(mode stpe needs no IMU)" in text and "--mode" not in text  # a command-line flag, in the viewer


def test_a_recording_shorter_than_acquire_s_that_never_registers_is_flagged_once_every_step_is_computed():
    z = np.zeros((2, 2), np.float32)
    f = Frame(20, 1_100_000, z, z, z, EventArray.empty(), EventArray.empty(), status="degraded", reason="few points")
    eng = _tracker_like([False] * 21)  # shown: 0.10 s, short of acquire-s
    eng.known_summaries, eng.n_steps = _tracker_like([False] * 61).history, 100
    assert "registered against this map" not in status_markdown(f, eng, {})  # 61 of 100 steps known: it may still
    eng.n_steps = 61  # the run-ahead has every step, 0.30 s from the first pose, and none registered
    assert "no update registered against this map in the whole recording (0.30 s)" in status_markdown(f, eng, {})
    eng.known_summaries = eng.known_summaries[:60] + [SimpleNamespace(t_us=1_300_000, counts={"registered": 1})]
    assert "registered against this map" not in status_markdown(f, eng, {})


def test_a_step_at_or_in_a_long_stretch_without_events_says_so(bar_recording):
    # A seek to 30 s in a recording without events from 2 to 62 s showed the tracker's step at 1.995 s (its steps
    # skip the gap) and the time slider jumped back there with nothing said; SLAM's steps in it read "waiting".
    from app.status import event_gaps

    t = np.array([0, 999_000, 1_998_000, 62_000_000, 62_000_500], np.int64)
    gaps = event_gaps(t)
    assert [(g.t_last_us, g.t_next_us) for g in gaps] == [(1_998_000, 62_000_000)]  # under a second is no gap
    eng = EventsOnlyEngine(bar_recording)
    z = np.zeros((2, 2), np.float32)
    at = lambda t_us: Frame(3, t_us, z, z, z, EventArray.empty(), EventArray.empty())
    stats = {"state": "paused", "speed": 1.0}
    assert "this step lies in it" in status_markdown(at(30_000_000), eng, stats, gaps)
    assert "no events from 1.998 to 62.000 s (60.0 s): after this step" in status_markdown(at(1_995_000), eng, stats, gaps)
    tracker = SimpleNamespace(seconds_of_steps=lambda k: k, is_last=lambda f: False, n_steps=None)
    assert "the tracker's steps skip it (a seek into it shows the last step before it)" in status_markdown(at(1_995_000), tracker, stats, gaps)
    assert "no events" not in status_markdown(at(1_500_000), eng, stats, gaps)
    assert "no events" not in status_markdown(at(62_000_000), eng, stats, gaps)
    played = dict(stats, skipped_gap=(1_990_000, 62_030_000))
    assert "no events from 1.99 to 62.03 s (60.0 s): not waited for in real time" in status_markdown(at(62_500_000), eng, played, gaps)


def test_times_are_said_from_the_recordings_start_as_the_time_slider(bar_recording):
    # A recording on a clock of its own (first event at 100 s) read "t = 101.495 s" in the status line, the teaching
    # panel, SLAM's MCI time and the plots' time axis, beside a time slider at 1.495.
    import dataclasses

    from app.plots import plot_series
    from app.teaching import Stage, live_facts
    from app.frame import StepSummary

    ev = bar_recording.events
    rec = dataclasses.replace(bar_recording, events=EventArray(ev.t + 100_000_000, ev.x, ev.y, ev.p))
    eng = EventsOnlyEngine(rec)
    z = np.zeros((2, 2), np.float32)
    f = Frame(3, eng.t_start_us + 1_495_000, z, z, z, EventArray.empty(), EventArray.empty())
    assert status_markdown(f, eng, {"state": "paused", "speed": 1.0}).startswith("t = 1.495 s, step 3")
    assert "At t = 1.495 s (step 3)" in live_facts(Stage.EVENTS, f, eng.t_start_us)
    steps = [StepSummary(i, eng.t_start_us + i * 5_000, None, None, "ok", {}, {"events_in": 1}) for i in range(3)]
    t = plot_series(steps, None, t0_us=eng.t_start_us)["events per second"][1][0]
    assert np.allclose(t, [0.0, 0.005, 0.01])
