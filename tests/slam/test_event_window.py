import numpy as np

from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig
from evpose.slam.event_window import EventWindowSelector, WindowEvent
from slam_synthetic import make_recording


def _run(rec, cfg=None):
    sel = EventWindowSelector(cfg or EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180)
    ev = rec.events
    out = sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
    return sel, out


def test_tiny_window_size_shrinks_for_a_fast_camera_and_grows_for_a_slow_one():
    fast, out_fast = _run(make_recording(duration_s=0.5, speed=3.0, seed=1))
    slow, out_slow = _run(make_recording(duration_s=0.5, speed=0.4, seed=1))
    assert len(out_fast) > len(out_slow) >= 1
    # eq. (8) keeps about N_x tiny frames per window: the fast camera needs fewer events per frame.
    assert fast.n_events < slow.n_events
    assert fast.n_events_history[-1] <= max(fast.n_events_history[1:3])
    assert all(abs(w.n_frames - 3) <= 1 for w in out_fast[3:])


def test_windows_are_triggered_by_feature_displacement_and_overlap():
    sel, out = _run(make_recording(duration_s=0.4, speed=2.0, seed=2))
    assert len(out) >= 3
    for w in out:
        assert w.median_displacement_px > 4.0 and not w.forced
        assert np.all(np.diff(w.t) >= 0)
        assert len(w.ref_pts) == len(w.cur_pts) >= 8
    # 50 % overlap: each MCI window is the previous trigger window plus the new one.
    for a, b in zip(out[:-1], out[1:]):
        assert a.t[0] <= b.t[0] < a.t[-1] < b.t[-1]
        shared = np.intersect1d(a.t, b.t).size
        assert shared > 0


def test_still_camera_yields_no_window_and_reports_low_rate():
    sel, out = _run(make_recording(duration_s=0.3, still=True))
    assert out == []
    assert sel.last_event is WindowEvent.LOW_RATE


def test_selector_is_deterministic_across_push_chunking():
    rec = make_recording(duration_s=0.3, speed=2.0, seed=4)
    _, whole = _run(rec)
    sel = EventWindowSelector(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180)
    ev = rec.events
    parts = []
    for a in range(0, len(ev), 7777):
        b = min(a + 7777, len(ev))
        parts += sel.push(ev.t[a:b], ev.x[a:b].astype(float), ev.y[a:b].astype(float), ev.p[a:b])
    assert len(parts) == len(whole)
    for a, b in zip(parts, whole):
        assert np.array_equal(a.t, b.t) and np.array_equal(a.cur_pts, b.cur_pts)


def _with_dropout(rec, t0_us: int, t1_us: int):
    """``rec``'s events with nothing at all in ``[t0_us, t1_us)`` (a sensor or transfer dropout)."""
    ev = rec.events
    keep = (ev.t < t0_us) | (ev.t >= t1_us)
    return ev[keep]


def test_no_window_spans_a_dropout_longer_than_max_event_gap():
    rec = make_recording(duration_s=0.8, speed=2.0, seed=3)
    ev = _with_dropout(rec, 400_000, 460_000)
    sel = EventWindowSelector(EventWindowConfig(max_event_gap_ms=20.0), FeatureConfig(), EventImageConfig(), 240, 180)
    out = []
    for a in range(0, len(ev), 5000):  # the dropout falls inside one push and between others
        b = min(a + 5000, len(ev))
        out += sel.push(ev.t[a:b], ev.x[a:b].astype(float), ev.y[a:b].astype(float), ev.p[a:b])
    assert any(w.t[-1] < 400_000 for w in out) and any(w.t[0] >= 460_000 for w in out)
    # Neither the windows' own events nor the overlap carried from the previous window cross the gap.
    assert all(w.t[-1] < 400_000 or w.t[0] >= 460_000 for w in out)


def test_a_dropout_is_ignored_when_the_gap_rule_is_off():
    rec = make_recording(duration_s=0.8, speed=2.0, seed=3)
    ev = _with_dropout(rec, 400_000, 460_000)
    sel = EventWindowSelector(EventWindowConfig(max_event_gap_ms=0.0), FeatureConfig(), EventImageConfig(), 240, 180)
    out = sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
    assert any(w.t[0] < 400_000 <= w.t[-1] for w in out)


def test_time_the_window_spent_below_the_event_rate_is_reported_with_the_next_window():
    rec = make_recording(duration_s=1.0, speed=2.0, seed=3)
    ev = rec.events
    # A blank wall from 400 to 700 ms: only every 50th event is left, about half th_e.
    inside = (ev.t >= 400_000) & (ev.t < 700_000)
    ev = ev[~inside | (np.arange(len(ev)) % 50 == 0)]
    # Tiny windows of 1000 events: the blank fills several of them (adapted ones grow past the blank's events).
    cfg = EventWindowConfig(initial_events=1000, max_events=1000)
    sel = EventWindowSelector(cfg, FeatureConfig(), EventImageConfig(), 240, 180)
    out = sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
    before = [w for w in out if w.t[-1] < 400_000]
    after = [w for w in out if w.t[-1] >= 700_000]
    assert before and len(after) >= 2 and all(w.blank_us == 0 for w in before)
    # Most of the blank, and never more than the time between the windows around it.
    assert 250_000 <= after[0].blank_us <= after[0].t[0] - before[-1].t[-1]
    assert all(w.blank_us == 0 for w in after[1:])


def test_carried_tracks_span_each_window_from_the_previous_windows_reference_frame():
    rec = make_recording(duration_s=0.4, speed=2.0, seed=2)
    ev = rec.events
    plain = EventWindowSelector(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180)
    carry = EventWindowSelector(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180, carry_tracks=True)
    a = plain.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
    b = carry.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
    assert len(a) == len(b) >= 3
    # Carrying changes nothing else about the windows.
    for u, v in zip(a, b):
        assert np.array_equal(u.t, v.t) and np.array_equal(u.ref_pts, v.ref_pts) and np.array_equal(u.cur_pts, v.cur_pts)
        assert u.whole_pts.size == 0 and u.whole_t_us.size == 0
    assert b[0].whole_pts.size == 0  # the first window has no overlap
    for prev, w in zip(b[:-1], b[1:]):
        F, M, _ = w.whole_pts.shape
        assert M >= 8 and F == len(w.whole_t_us) == prev.n_frames + w.n_frames
        assert w.whole_t_us[0] == prev.t_ref_us and w.whole_t_us[-1] == w.t_cur_us
        # They start where the previous window's features were and move farther than this window's own tracks.
        assert all(np.any(np.all(prev.ref_pts == p, axis=1)) for p in w.whole_pts[0])
        whole = np.median(np.linalg.norm(w.whole_pts[-1] - w.whole_pts[0], axis=1))
        assert whole > 1.5 * w.median_displacement_px
