"""front_end_at: the tracker's SP-TS images and noise-filter split at any update, rebuilt from recent events only."""

import dataclasses

import numpy as np
import pytest
from tracker_synthetic import generate

from evpose.frontend.time_surface import TimeSurfaceConfig
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.front_end_view import front_end_at, replay_span_us
from evpose.tracker.session import TrackingSession


@pytest.fixture(scope="module")
def scene():
    rec, cmap, _ = generate(duration_s=0.2, seed=3)
    return rec, cmap


def _reference(rec, cmap, cfg, steps):
    """Debug products of a headless run at ``steps``."""
    s = TrackingSession(rec, cmap, cfg)
    out = {}
    for k in range(max(steps) + 1):
        r = s.step(debug=k in steps)
        if k in steps:
            out[k] = r
    return s, out


@pytest.mark.parametrize("eta_ms", [0.5, 10.0])
def test_front_end_view_equals_the_trackers_images_at_any_update(scene, eta_ms):
    # eta 0.5 ms: the replay span (~57 ms) is shorter than the run, so updates past it replay only recent events;
    # eta 10 ms: the span reaches back to the warm-up, so the whole history is replayed.
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE, time_surface=TimeSurfaceConfig(eta_ms=eta_ms))
    steps = (0, 1, 17, 30)
    session, ref = _reference(rec, cmap, cfg, steps)
    if eta_ms < 1:
        assert replay_span_us(cfg) < 17 * session.dt_us
    for k in steps:
        v = front_end_at(session, k)
        d = ref[k].debug
        assert v.exact and v.t_us == ref[k].t_us
        assert v.ts_positive.dtype == np.float32 and v.ts_positive.shape == d.ts_positive.shape
        assert np.array_equal(v.ts_positive, d.ts_positive) and np.array_equal(v.ts_negative, d.ts_negative)
        assert np.array_equal(v.events_kept.t, d.events_kept.t) and np.array_equal(v.events_removed.t, d.events_removed.t)
        assert v.tdf.shape == d.tdf.shape and np.all((v.tdf >= 0) & (v.tdf <= 1))


def test_front_end_view_leaves_the_session_untouched(scene):
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE)
    s = TrackingSession(rec, cmap, cfg)
    s.step()
    before = s.tracker.snapshot()
    front_end_at(s, 25)
    after = s.tracker.snapshot()
    assert s.step_count == 1
    assert np.array_equal(before["time_surface"]["last"], after["time_surface"]["last"])
    assert np.array_equal(before["noise_filter"]["last"], after["noise_filter"]["last"])


def test_front_end_view_is_not_exact_with_the_pose_reading_ego_motion_filter(scene):
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE)
    cfg = dataclasses.replace(cfg, ego_motion=dataclasses.replace(cfg.ego_motion, enabled=True))
    assert not front_end_at(TrackingSession(rec, cmap, cfg), 3).exact
