"""Events-only engine: seeking lands on exactly the state an uninterrupted run reaches (tracker: test_tracker_engine.py)."""

import numpy as np

from app.engine import EventsOnlyEngine, EventsViewConfig


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


def test_a_seek_keeps_the_timings_of_the_steps_already_computed(bar_recording):
    # Stepping forward after playing seeks: the played steps' latencies stay on the plot.
    eng = EventsOnlyEngine(bar_recording)
    frames = [eng.step() for _ in range(20)]
    f = eng.seek(frames[12].t_us)
    assert f.index == 12
    assert all(s.timings_ms for s in eng.history) and len(eng.history) == 13
    fresh = EventsOnlyEngine(bar_recording)
    fresh.seek(frames[12].t_us)
    assert [s.counts for s in eng.history] == [s.counts for s in fresh.history]
    assert not any(s.timings_ms for s in fresh.history[:12])  # never computed: untimed


def test_events_only_play_goes_over_windows_without_events_and_keeps_their_summaries(bar_recording):
    # Made one by one, with images and a field each, a 60 s gap took over a minute to play with nothing to see.
    import dataclasses

    from evpose.core.events import EventArray

    ev = bar_recording.events
    t = ev.t.copy()
    t[t >= 300_000] += 2_000_000  # no events from 0.3 to 2.3 s
    rec = dataclasses.replace(bar_recording, events=EventArray(t, ev.x, ev.y, ev.p))
    one, played = EventsOnlyEngine(rec), EventsOnlyEngine(rec)
    frames = list(iter(one.step, None))
    shown = list(iter(lambda: played.play_step(1), None))
    assert [(s.index, s.t_us, s.counts) for s in played.history] == [(s.index, s.t_us, s.counts) for s in one.history]
    assert len(shown) < len(frames) - 300  # at most 1 s of empty windows in one call: 400 empty ones, 2 calls
    first = next(f for f in frames if f.index > 60 and f.counts["events_in"])
    again = next(f for f in shown if f.index == first.index)
    assert np.array_equal(again.tdf, first.tdf) and np.array_equal(again.ts_positive, first.ts_positive)
