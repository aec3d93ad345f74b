"""The end of the event stream: the events after the last reconstruction window become one more MCI
(``EventWindowConfig.flush_min_fraction``) instead of being dropped."""

from dataclasses import replace

import numpy as np

from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig, SlamConfig
from evpose.slam.event_window import EventWindowSelector
from evpose.slam.run import run_slam
from slam_synthetic import make_recording


def _selector(frac: float) -> EventWindowSelector:
    return EventWindowSelector(EventWindowConfig(flush_min_fraction=frac), FeatureConfig(), EventImageConfig(), 240, 180)


def _push(sel, ev, n):
    return sel.push(ev.t[:n], ev.x[:n].astype(float), ev.y[:n].astype(float), ev.p[:n])


def _cut_inside_a_window():
    """A synthetic recording and an event count that ends the stream 80 % of the way through its 5th window's own
    events (so the tail holds far more than half a window), with the windows the whole stream makes."""
    rec = make_recording(duration_s=0.4, speed=2.0, seed=2)
    ev = rec.events
    whole = _push(_selector(0.0), ev, len(ev))
    assert len(whole) >= 5
    a, b = int(whole[3].t[-1]), int(whole[4].t[-1])
    n = int(np.searchsorted(ev.t, a + 0.8 * (b - a), side="right"))
    return ev, n, whole


def test_the_tail_after_the_last_window_is_flushed_as_one_forced_window():
    ev, n, whole = _cut_inside_a_window()
    sel = _selector(0.5)
    out = _push(sel, ev, n)
    assert len(out) == 4 and np.array_equal(out[-1].t, whole[3].t)
    rw = sel.flush()
    assert rw is not None and rw.forced
    # It continues the last window: the overlap is that window's own part, then the tail's events up to the end.
    assert rw.t[0] > out[-1].t[0] and rw.t[0] <= out[-1].t[-1] < rw.t[-1] <= ev.t[n - 1]
    assert np.intersect1d(rw.t, out[-1].t).size > 0
    assert len(rw.ref_pts) == len(rw.cur_pts) >= 8
    # Nothing is left to flush twice.
    assert sel.flush() is None


def test_no_flush_when_off_or_when_the_tail_is_too_small():
    ev, n, _ = _cut_inside_a_window()
    off = _selector(0.0)
    _push(off, ev, n)
    assert off.flush() is None
    # A tail must hold flush_min_fraction of the last window's own events: 10x that window never qualifies.
    big = _selector(10.0)
    _push(big, ev, n)
    assert big.flush() is None


def test_run_slam_tracks_the_tail_of_the_recording():
    rec = make_recording(duration_s=0.6, speed=2.0, seed=3)
    base = SlamConfig()
    off = run_slam(rec, replace(base, window=replace(base.window, flush_min_fraction=0.0)))
    on = run_slam(rec, replace(base, window=replace(base.window, flush_min_fraction=0.5)))
    # The same MCIs up to the end of the stream, then one more from the events after the last window.
    assert len(on.results) == len(off.results) + 1
    assert [r.t_us for r in on.results[:-1]] == [r.t_us for r in off.results]
    assert off.results[-1].t_us < on.results[-1].t_us <= int(rec.events.t[-1])
    assert on.results[-1].mci is not None and on.results[-1].status.value == "ok" and on.results[-1].pose is not None
