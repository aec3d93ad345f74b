"""Frame cache: 8-bit frames draw exactly like float ones; the budget drops the frames farthest from the shown step."""

import numpy as np

from app.frame import Frame
from app.frame_cache import FrameCache, compact, frame_nbytes, quantize, unit
from app.panels import OverlayColour, panel_images
from evpose.core.events import EventArray


def _frame(index, rng, h=20, w=30):
    img = lambda: rng.random((h, w)).astype(np.float32) * 1.2 - 0.1  # noqa: E731 (values outside [0, 1] too)
    uv = rng.random((15, 2)).astype(np.float32) * [w, h]
    return Frame(index, 1000 * index, img(), img(), img(), EventArray.empty(), EventArray.empty(),
                 projected_uv=uv, residuals=rng.random(15).astype(np.float32), weights=rng.random(15).astype(np.float32),
                 predicted_polarity=rng.integers(-1, 2, 15).astype(np.int8))


def test_compact_frames_draw_pixel_identical_panels():
    f = _frame(3, np.random.default_rng(0))
    c = compact(f)
    assert c.tdf.dtype == np.uint8 and frame_nbytes(c) < frame_nbytes(f)
    for colour in OverlayColour:
        a, b = panel_images(f, colour), panel_images(c, colour)
        assert a.keys() == b.keys()
        for name in a:
            assert np.array_equal(a[name], b[name]), name


def test_cached_frames_come_back_equal_and_compressed():
    f = _frame(4, np.random.default_rng(2), h=120, w=160)
    f.ts_positive[:] = 0.0  # mostly empty, like a time surface
    cache = FrameCache(every_steps=1, budget_bytes=1 << 30)
    cache.put(f, near=0)
    g = cache.get(4)
    c = compact(f)
    for name in ("ts_positive", "ts_negative", "tdf", "projected_uv", "residuals", "weights", "predicted_polarity"):
        assert np.array_equal(getattr(g, name), getattr(c, name)) and getattr(g, name).dtype == getattr(c, name).dtype, name
    assert g.index == 4 and g.t_us == f.t_us
    assert cache.nbytes < frame_nbytes(c)
    assert not g.tdf.flags.writeable  # the cache's copy cannot be changed through a frame it handed out


def test_index_lists_round_trip_exactly_in_any_order_and_range():
    rng = np.random.default_rng(3)
    cache = FrameCache(every_steps=1, budget_bytes=1 << 30)
    cases = {0: np.sort(rng.choice(100_000, 5000, replace=False)).astype(np.int64),
             1: rng.integers(-2**40, 2**40, 3000).astype(np.int64),
             2: rng.permutation(4000).astype(np.int64)}
    for k, idx in cases.items():
        f = _frame(k, rng)
        f.visible_index = idx
        cache.put(f, near=0)
        got = cache.get(k).visible_index
        assert got.dtype == idx.dtype and np.array_equal(got, idx)
    assert cache._frames[0][0] < 40_000  # the sorted list is stored in far fewer bytes than its 40 kB


def test_quantize_and_unit_round_trip_within_one_level():
    x = np.linspace(-0.5, 1.5, 1001, dtype=np.float32)
    q = quantize(x)
    assert q.dtype == np.uint8 and q[0] == 0 and q[-1] == 255
    assert quantize(q) is q
    assert np.all(np.abs(unit(q) - np.clip(x, 0, 1)) <= 1 / 255 + 1e-7)


def test_budget_drops_the_frames_farthest_from_the_shown_step():
    rng = np.random.default_rng(1)
    probe = FrameCache(every_steps=2, budget_bytes=1 << 30)
    probe.put(_frame(0, rng), near=0)
    cache = FrameCache(every_steps=2, budget_bytes=int(3.5 * probe.nbytes))
    for k in range(0, 20, 2):
        cache.put(_frame(k, rng), near=10)
    assert len(cache) == 3 and cache.evicted == 7 and cache.nbytes <= cache.budget
    assert sorted(k for k in range(20) if k in cache) == [8, 10, 12]
    assert cache.latest_at_or_before(11, 0).index == 10
    assert cache.latest_at_or_before(7, 0) is None
