"""One KLT call for several point sets (``features.track_feature_sets``) gives each set what its own call gives, and
the window selector's carried tracks, tracked in one call with the window's own features, are those of one call each."""
import numpy as np

import evpose.slam.event_window as event_window
from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig
from evpose.slam.event_window import EventWindowSelector
from evpose.slam.features import track_feature_sets, track_features
from slam_synthetic import make_recording, shifted_image_pair

W, H = 160, 120


def _pair(rng, shift):
    return shifted_image_pair(rng, shift, W, H)


def test_track_feature_sets_equals_one_track_features_call_per_set():
    rng = np.random.default_rng(3)
    cfg = FeatureConfig()
    for k in range(10):
        a, b = _pair(rng, rng.uniform(-8, 8, 2))
        sizes = [int(rng.integers(0, 120)), 0 if k % 3 == 0 else int(rng.integers(1, 90))]
        sets = [np.c_[rng.uniform(0, W - 1, m), rng.uniform(0, H - 1, m)].astype(np.float32) for m in sizes]
        got = track_feature_sets(a, b, sets, cfg)
        assert len(got) == len(sets)
        for (new, ok), pts in zip(got, sets):
            ref, ok_ref = track_features(a, b, pts, cfg)
            assert new.dtype == ref.dtype and new.shape == ref.shape == (len(pts), 2)
            np.testing.assert_array_equal(new.view(np.uint32), ref.view(np.uint32))
            np.testing.assert_array_equal(ok, ok_ref)


def _one_call_per_set(prev8, cur8, sets, cfg):
    """The session-26 form before the merge: the window's and the carried features in separate calls."""
    return [track_features(prev8, cur8, p, cfg) for p in sets]


def test_carried_tracks_are_those_of_separate_klt_calls(monkeypatch):
    rec = make_recording(duration_s=0.4, speed=2.0, seed=2)
    ev = rec.events

    def run():
        sel = EventWindowSelector(EventWindowConfig(), FeatureConfig(), EventImageConfig(), 240, 180, carry_tracks=True)
        return sel.push(ev.t, ev.x.astype(float), ev.y.astype(float), ev.p)

    merged = run()
    monkeypatch.setattr(event_window, "track_feature_sets", _one_call_per_set)
    separate = run()
    assert len(merged) == len(separate) >= 3
    assert any(w.whole_pts.size for w in merged)
    for u, v in zip(merged, separate):
        for f in ("t", "ref_pts", "cur_pts", "whole_pts", "whole_t_us"):
            np.testing.assert_array_equal(getattr(u, f), getattr(v, f))
        assert u.median_displacement_px == v.median_displacement_px and u.n_frames == v.n_frames
