"""The distance field of T_align built from its patch list equals the one built from the composed image, bit for bit."""

import numpy as np
import pytest

from evpose.core.events import EventArray
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig
from evpose.fusion.aligned_field import fill_distance_field
from evpose.fusion.aligned_surface import AlignedTimeSurface

from fusion_helpers import ALIGNED_H as H, ALIGNED_K as K, ALIGNED_W as W, points_at as _points_at


def _random_step(rng, t_end):
    """A surface with events of both polarities spread over ~15 eta (some past the decay table) and random points."""
    n = 3000
    t = np.sort(rng.integers(t_end - 150_000, t_end, n)).astype(np.int64)
    ev = EventArray.from_arrays(t=t, x=rng.integers(0, W, n).astype(np.uint16), y=rng.integers(0, H, n).astype(np.uint16),
                                p=rng.choice(np.array([-1, 1], np.int8), n))
    s = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=10.0), W, H)
    s.update(ev)
    uv = np.stack([rng.uniform(-3, W + 3, 40), rng.uniform(-3, H + 3, 40)], 1)
    return s, ev, _points_at(uv), rng.integers(-1, 2, 40).astype(np.int8)


def _same_field(a: TemporalDistanceField, b: TemporalDistanceField) -> bool:
    if a.slots_ready != b.slots_ready or not np.array_equal(a.box, b.box) or a.t_us != b.t_us:
        return False
    r0, r1, c0, c1 = (int(v) for v in a.box)
    box = (slice(r0, r1), slice(c0, c1))
    arrays = [(a.value[0], b.value[0]), (a.grad_u[0], b.grad_u[0]), (a.grad_v[0], b.grad_v[0])]
    arrays += [(a.hess[i, 0], b.hess[i, 0]) for i in range(3)]
    return all(np.array_equal(x[box], y[box]) for x, y in arrays)


@pytest.mark.parametrize("blur_px", [0, 3, 5])
@pytest.mark.parametrize("roi", [None, (5, 40, 3, 60), (-4, 30, 10, 80)])
def test_field_from_patch_list_equals_compute_over_the_composed_image(blur_px, roi):
    rng = np.random.default_rng(blur_px * 7 + (0 if roi is None else roi[0] + 10))
    a = AlignedTimeSurface(W, H)
    for step in range(3):  # reused between steps, as in the tracker
        s, ev, pts, pol = _random_step(rng, 1_000_000 + step * 5000)
        t_us = int(ev.t[-1]) + 700
        a.compose(s, pts, np.eye(4), K, pol, 4.0, roi, ev)
        fast = TemporalDistanceField(DistanceFieldConfig(blur_px=blur_px), W, H)
        fill_distance_field(a, fast, t_us, roi, curvature=True)
        ref = TemporalDistanceField(DistanceFieldConfig(blur_px=blur_px), W, H)
        ref.compute(a, t_us, (0,), roi, curvature=True)
        assert _same_field(fast, ref)
        r0, r1, c0, c1 = (int(v) for v in fast.box)
        assert fast.value[0, r0:r1, c0:c1].min() < 0.9  # recent events inside the patches show


def test_field_of_a_box_too_small_is_empty():
    rng = np.random.default_rng(1)
    s, ev, pts, pol = _random_step(rng, 1_000_000)
    a = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 4.0, None, ev)
    f = TemporalDistanceField(DistanceFieldConfig(), W, H)
    fill_distance_field(a, f, int(ev.t[-1]), (10, 11, 0, W))
    assert f.slots_ready == () and not f.box.any() and f.t_us == int(ev.t[-1])


def test_composed_image_is_rebuilt_only_from_the_last_compose():
    # The image is built on demand; pixels of an earlier compose it was built for must not leak into a later one.
    rng = np.random.default_rng(2)
    s, ev, pts, pol = _random_step(rng, 1_000_000)
    a = AlignedTimeSurface(W, H)
    a.compose(s, _points_at([(12.0, 11.0), (40.0, 30.0)]), np.eye(4), K, np.array([0, 0], np.int8), 6.0, None, ev)
    first = a.last_of(0).copy()
    a.compose(s, pts, np.eye(4), K, pol, 3.0, None, ev)
    fresh = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 3.0, None, ev)
    assert np.array_equal(a.last_of(0), fresh.last_of(0)) and not np.array_equal(first, fresh.last_of(0))
    pixels, times = a.patch_times()
    assert np.array_equal(a.last_of(0)[pixels[:, 0], pixels[:, 1]], times)


def test_field_stays_exact_when_the_box_changes_size_between_steps_on_one_field():
    """The scratch rows are reused at every box size (growing, shrinking, full-width or not), as the tracker's box moves."""
    rng = np.random.default_rng(11)
    a = AlignedTimeSurface(W, H)
    fast = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
    for step, roi in enumerate([(5, 40, 3, 60), (0, H, 0, W), (10, 20, 20, 30), (2, 46, 0, W), (0, H, 1, W - 1), (5, 40, 3, 60)]):
        s, ev, pts, pol = _random_step(rng, 1_000_000 + step * 5000)
        t_us = int(ev.t[-1]) + 700
        a.compose(s, pts, np.eye(4), K, pol, 4.0, roi, ev)
        fill_distance_field(a, fast, t_us, roi, curvature=True)
        ref = TemporalDistanceField(DistanceFieldConfig(blur_px=5), W, H)
        ref.compute(a, t_us, (0,), roi, curvature=True)
        assert _same_field(fast, ref), roi


def test_tracker_setting_field_in_one_pass_equals_compute_as_the_box_moves():
    """3 px blur without curvature (the tracker's setting) takes the one-pass path with its persistent TDF scratch:
    every box of a moving sequence (growing, shrinking, at the borders, 2 px wide) must still equal ``compute``."""
    rng = np.random.default_rng(19)
    a = AlignedTimeSurface(W, H)
    fast = TemporalDistanceField(DistanceFieldConfig(blur_px=3), W, H)
    rois = [None, (5, 40, 3, 60), (0, H, 0, W), (10, 12, 20, 30), (2, 46, 0, 2), (0, H, 1, W - 1), None, (-3, 9, W - 9, W + 4)]
    for step, roi in enumerate(rois):
        s, ev, pts, pol = _random_step(rng, 1_000_000 + step * 5000)
        t_us = int(ev.t[-1]) + 700
        a.compose(s, pts, np.eye(4), K, pol, 4.0, roi, ev)
        fill_distance_field(a, fast, t_us, roi, curvature=False)
        ref = TemporalDistanceField(DistanceFieldConfig(blur_px=3), W, H)
        ref.compute(a, t_us, (0,), roi, curvature=False)
        assert _same_field(fast, ref), roi
