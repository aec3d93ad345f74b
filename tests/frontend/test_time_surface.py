"""SP-TS: per-polarity last timestamps, exponential decay, combined max, undistorted coordinates."""

import numpy as np

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

W, H = 64, 48


def test_time_surface_decays_exponentially_per_polarity():
    ts = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=10.0), W, H)
    ts.update(EventArray.from_arrays([1_000, 6_000], [3, 4], [5, 5], [1, -1]))
    pos = ts.image(11_000, 1)
    neg = ts.image(11_000, -1)
    assert np.isclose(pos[5, 3], np.exp(-1.0), atol=1e-6)
    assert np.isclose(neg[5, 4], np.exp(-0.5), atol=1e-6)
    assert pos[5, 4] == 0.0 and neg[5, 3] == 0.0
    assert pos.dtype == np.float32 and pos.shape == (H, W)


def test_combined_time_surface_is_the_max_of_both_polarities():
    rng = np.random.default_rng(0)
    n = 2000
    t = np.sort(rng.integers(0, 50_000, n))
    ev = EventArray.from_arrays(t, rng.integers(0, W, n), rng.integers(0, H, n), np.where(rng.random(n) < 0.5, 1, -1))
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    ts.update(ev)
    assert np.array_equal(ts.image(50_000, 0), np.maximum(ts.image(50_000, 1), ts.image(50_000, -1)))
    assert np.array_equal(ts.combined_last(), ts.last_timestamps.max(axis=0))


def test_time_surface_is_one_on_the_newest_events_and_zero_where_nothing_fired():
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    ts.update(EventArray.from_arrays([100, 200], [1, 2], [1, 1], [1, 1]))
    img = ts.image(200, 0)
    assert img[1, 2] == 1.0
    assert img[10, 10] == 0.0


def test_time_surface_masked_update_ignores_removed_events():
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    ev = EventArray.from_arrays([100, 200], [1, 2], [1, 1], [1, 1])
    assert ts.update(ev, np.array([True, False])) == 1
    assert ts.image(200, 1)[1, 2] == 0.0


def test_time_surface_stores_events_at_undistorted_pixels():
    cal = CameraCalibration(W, H, 50.0, 50.0, 31.5, 23.5, DistortionModel.RADTAN, (-0.3, 0.05, 0.0, 0.0, 0.0))
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), W, H, cal)
    x, y = 2, 3  # a corner pixel moves most under distortion
    ts.update(EventArray.from_arrays([10], [x], [y], [1]))
    ideal = cal.undistort_pixels(np.array([[x, y]]))[0]
    col, row = np.rint(ideal).astype(int)
    expect_inside = 0 <= col < W and 0 <= row < H
    hit = np.argwhere(ts.last_timestamps[0] == 10)
    if expect_inside:
        assert hit.tolist() == [[row, col]]
    else:
        assert hit.size == 0
    # The centre pixel barely moves.
    ts.update(EventArray.from_arrays([20], [32], [24], [-1]))
    c = cal.undistort_pixels(np.array([[32, 24]]))[0]
    assert ts.last_timestamps[1][int(np.rint(c[1])), int(np.rint(c[0]))] == 20


def test_time_surface_snapshot_restore():
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    ts.update(EventArray.from_arrays([100], [1], [1], [1]))
    snap = ts.snapshot()
    ts.update(EventArray.from_arrays([200], [5], [5], [-1]))
    ts.restore(snap)
    assert ts.last_timestamps[1].max() < 0 and ts.combined_last()[5, 5] < 0
