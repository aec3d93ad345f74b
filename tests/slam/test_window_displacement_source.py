"""The displacement test of the window selection reads ``M_fd`` through one method, so a measurement of another source
(the ground-truth displacement of session 27's oracle, ``/tmp/s27/room27/oexp.py``) drives the dispatch and eq. (8)."""
import numpy as np

from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig
from evpose.slam.event_window import EventWindowSelector
from slam_synthetic import make_recording


class _Constant(EventWindowSelector):
    def __init__(self, value_px: float, **kw):
        super().__init__(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180, **kw)
        self.value_px = value_px

    def _median_displacement(self, alive: np.ndarray) -> float:
        return self.value_px


def _push(sel, rec):
    ev = rec.events
    return sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)


def test_default_displacement_is_the_median_klt_displacement_of_the_live_features():
    sel = EventWindowSelector(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180)
    out = _push(sel, make_recording(duration_s=0.4, speed=2.0, seed=2))
    assert out
    for w in out:
        d = np.median(np.linalg.norm(w.cur_pts - w.ref_pts, axis=1))
        assert w.forced or np.isclose(w.median_displacement_px, d, atol=1e-5)


def test_a_large_displacement_dispatches_every_second_tiny_frame_and_shrinks_the_window():
    sel = _Constant(10.0)
    out = _push(sel, make_recording(duration_s=0.4, speed=2.0, seed=2))
    unforced = [w for w in out if not w.forced]
    assert unforced and all(w.n_frames == 2 and w.median_displacement_px == 10.0 for w in unforced)
    # eq. (8): 2 frames against N_x = 3 -> N_e shrinks to its clamp.
    assert sel.n_events_history[-1] == EventWindowConfig().min_events


def test_no_displacement_never_triggers_a_window_before_the_frame_cap():
    sel = _Constant(0.0)
    out = _push(sel, make_recording(duration_s=0.4, speed=2.0, seed=2))
    assert all(w.forced for w in out)
    assert sel.n_events_history == [EventWindowConfig().initial_events]
