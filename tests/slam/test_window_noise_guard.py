"""``EventWindowConfig.noise_residual_px``: a window whose feature displacement is KLT noise does not shrink ``N_e``."""

import numpy as np

from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig
from evpose.slam.event_window import EventWindowSelector
from slam_synthetic import make_recording


def _selector(limit: float) -> EventWindowSelector:
    return EventWindowSelector(EventWindowConfig(noise_residual_px=limit), FeatureConfig(), EventImageConfig(), 240, 180)


def _set_tracks(sel: EventWindowSelector, ref: np.ndarray, cur: np.ndarray) -> None:
    s = sel.state
    s.ref_pts, s.cur_pts, s.alive = ref.astype(np.float32), cur.astype(np.float32), np.ones(len(ref), bool)


def test_coherent_motion_is_not_noise_but_scattered_tracks_are():
    rng = np.random.default_rng(0)
    ref = rng.uniform(20, 200, (30, 2))
    sel = _selector(2.0)
    # A rotation, zoom and shift of 5 px: every track on one similarity.
    c, s_ = np.cos(0.02) * 1.01, np.sin(0.02) * 1.01
    _set_tracks(sel, ref, ref @ np.array([[c, s_], [-s_, c]]) + [4.0, 3.0])
    assert not sel._incoherent()
    # The same median displacement scattered in random directions: KLT jitter on a few hundred events.
    ang = rng.uniform(0, 2 * np.pi, len(ref))
    _set_tracks(sel, ref, ref + 5.0 * np.c_[np.cos(ang), np.sin(ang)])
    assert sel._incoherent()
    off = _selector(0.0)
    _set_tracks(off, ref, ref + 5.0 * np.c_[np.cos(ang), np.sin(ang)])
    assert not off._incoherent()  # 0: off


def test_off_by_default_and_a_noise_window_keeps_its_tiny_window_size():
    assert EventWindowConfig().noise_residual_px == 0.0
    rec = make_recording(duration_s=0.5, speed=3.0, seed=1)
    ev = rec.events
    runs = {}
    for limit in (0.0, 1e-3, 50.0):
        sel = _selector(limit)
        out = sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)
        runs[limit] = (sel, out)
    off, every, never = runs[0.0], runs[1e-3], runs[50.0]
    assert len(off[1]) >= 3 and len(every[1]) >= 3
    # Every window judged noise: eq. (8) never runs, N_e stays at its initial size.
    assert set(every[0].n_events_history) == {EventWindowConfig().initial_events}
    assert len(set(off[0].n_events_history)) > 1
    # A limit no track scatter reaches leaves the selection as it is without the guard.
    assert off[0].n_events_history == never[0].n_events_history
    assert len(off[1]) == len(never[1]) and all(np.array_equal(a.t, b.t) for a, b in zip(off[1], never[1]))
