"""T_align: the SP-TS seen through each map point's patch and predicted polarity (the polarity event filter)."""

import numpy as np

from evpose.core.events import EventArray
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.frontend.noise_filter import NEVER_US
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig
from evpose.fusion.aligned_surface import AlignedTimeSurface
from evpose.fusion.polarity import classify_events

from fusion_helpers import ALIGNED_H as H, ALIGNED_K as K, ALIGNED_W as W, points_at as _points_at


def _events(xs, ys, ps, t0=1000):
    n = len(xs)
    return EventArray.from_arrays(t=np.arange(t0, t0 + n, dtype=np.int64), x=np.asarray(xs, np.uint16), y=np.asarray(ys, np.uint16),
                                  p=np.asarray(ps, np.int8))


def _surface(ev):
    s = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    s.update(ev)
    return s


def test_patch_reads_only_the_predicted_polarity_and_nothing_outside_patches():
    # ON event at (10, 10), OFF event at (11, 10), both near a point predicted ON; an ON event far from any point.
    ev = _events([10, 11, 40], [10, 10, 30], [1, -1, 1])
    s = _surface(ev)
    a = AlignedTimeSurface(W, H).compose(s, _points_at([(10.5, 10.0)]), np.eye(4), K, np.array([1], np.int8), 3.0, None, ev)
    last = a.last_of(0)
    assert last[10, 10] == s.last_of(1)[10, 10]
    assert last[10, 11] == NEVER_US  # OFF event hidden: the point predicts ON
    assert last[30, 40] == NEVER_US  # no map point near: not shown to registration
    assert a.last_counts["events_polarity_judged"] == 3
    assert a.last_counts["events_outside_patches"] == 1
    assert a.last_counts["events_wrong_polarity"] == 1
    assert a.last_counts["events_polarity_removed"] == 2


def test_buffer_zone_point_keeps_both_polarities():
    ev = _events([10, 11], [10, 10], [1, -1])
    s = _surface(ev)
    a = AlignedTimeSurface(W, H).compose(s, _points_at([(10.5, 10.0)]), np.eye(4), K, np.array([0], np.int8), 3.0, None, ev)
    assert a.last_of(0)[10, 10] == s.last_of(0)[10, 10] and a.last_of(0)[10, 11] == s.last_of(0)[10, 11]
    assert a.last_counts["events_polarity_removed"] == 0


def test_overlapping_patches_take_the_nearest_points_polarity():
    # An ON point at column 10 and an OFF point at column 16, patches of 5 px overlap in between.
    ev = _events([12, 12, 14, 14], [20, 20, 20, 20], [1, -1, 1, -1])
    s = _surface(ev)
    pts = _points_at([(10.0, 20.0), (16.0, 20.0)])
    a = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, np.array([1, -1], np.int8), 5.0, None, ev)
    assert a.accept[20, 12] == 1 and a.accept[20, 14] == 2
    assert a.last_of(0)[20, 12] == s.last_of(1)[20, 12]
    assert a.last_of(0)[20, 14] == s.last_of(-1)[20, 14]


def test_distance_field_over_aligned_surface_is_one_outside_patches():
    ev = _events([10, 40], [10, 30], [1, 1], t0=5000)
    s = _surface(ev)
    a = AlignedTimeSurface(W, H).compose(s, _points_at([(10.0, 10.0)]), np.eye(4), K, np.array([1], np.int8), 3.0, None)
    f = TemporalDistanceField(DistanceFieldConfig(blur_px=0), W, H)
    f.compute(a, 5010, (0,), None, curvature=False)
    img = f.image(0)
    assert img[10, 10] < 0.01
    assert img[30, 40] == 1.0


def test_classify_agrees_with_classify_events_at_the_same_pose():
    rng = np.random.default_rng(3)
    uv = np.stack([rng.uniform(5, W - 5, 30), rng.uniform(5, H - 5, 30)], 1)
    pol = rng.integers(-1, 2, 30).astype(np.int8)
    ev = _events(rng.integers(0, W, 400), rng.integers(0, H, 400), rng.choice([-1, 1], 400))
    a = AlignedTimeSurface(W, H).compose(_surface(ev), _points_at(uv), np.eye(4), K, pol, 4.0, None)
    label, point = a.classify(ev, 2.0)
    ref_label, ref_point = classify_events(ev.x, ev.y, ev.p, uv, pol, 2.0, W, H)
    # Equidistant points may be resolved differently; everything else matches.
    assert np.mean(label == ref_label) > 0.98 and np.mean(point == ref_point) > 0.98


def test_compose_is_deterministic_and_stateless():
    ev = _events([10, 11, 20], [10, 10, 20], [1, -1, -1])
    s = _surface(ev)
    pts = _points_at([(10.0, 10.0), (20.0, 20.0)])
    pol = np.array([1, -1], np.int8)
    a = AlignedTimeSurface(W, H)
    a.compose(s, _points_at([(40.0, 30.0), (12.0, 11.0)]), np.eye(4), K, np.array([0, -1], np.int8), 6.0, None, ev)  # an earlier step
    again = a.compose(s, pts, np.eye(4), K, pol, 3.0, (0, 30, 0, 30), ev)
    fresh = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 3.0, (0, 30, 0, 30), ev)
    assert np.array_equal(again.last_of(0), fresh.last_of(0)) and np.array_equal(again.accept, fresh.accept)
    assert again.last_counts == fresh.last_counts


def test_points_whose_patch_shows_no_recent_accepted_event_are_marked_empty():
    # Point 0: a fresh ON event in its patch. Point 1: only an OFF event (it predicts ON). Point 2: an ON event
    # 50 ms old (5 eta). Point 3: nothing.
    s = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=10.0), W, H)
    s.update(_events([30], [40], [1], t0=10_000))
    s.update(_events([10, 20], [10, 10], [1, -1], t0=59_000))
    pts = _points_at([(10.0, 10.0), (20.0, 10.0), (30.0, 40.0), (50.0, 30.0)])
    a = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, np.array([1, 1, 1, 1], np.int8), 3.0, None,
                                         t_us=60_000, empty_after_eta=3.0)
    assert a.point_has_events.tolist() == [True, False, False, False]
    assert a.last_counts["points_with_events"] == 1


def test_compose_after_the_generation_tags_wrap_equals_a_fresh_one():
    import evpose.fusion.aligned_surface as aligned

    ev = _events([10, 11, 20], [10, 10, 20], [1, -1, -1])
    s = _surface(ev)
    pts = _points_at([(10.0, 10.0), (20.0, 20.0)])
    pol = np.array([1, -1], np.int8)
    a = AlignedTimeSurface(W, H)
    a.compose(s, _points_at([(12.0, 11.0), (30.0, 30.0)]), np.eye(4), K, np.array([0, 1], np.int8), 6.0, None, ev)
    a._gen = aligned._MAX_GENERATION  # the next compose wraps the tags around
    again = a.compose(s, pts, np.eye(4), K, pol, 3.0, None, ev)
    fresh = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 3.0, None, ev)
    assert np.array_equal(again.last_of(0), fresh.last_of(0)) and np.array_equal(again.accept, fresh.accept)
    assert again.last_counts == fresh.last_counts
    assert all(np.array_equal(x, y) for x, y in zip(again.classify(ev, 2.0), fresh.classify(ev, 2.0)))


def _nearest_point_reference(uv, pol, radius, box):
    """Brute force over every pixel of the box: polarity flags of all nearest points within ``radius`` (float32
    squared distances, as the kernel rounds them), the smallest index of them, its squared distance."""
    flag = np.zeros((H, W), np.uint8)
    owner = np.full((H, W), -1, np.int64)
    best = np.full((H, W), np.inf, np.float32)
    bits = np.where(pol > 0, 1, np.where(pol < 0, 2, 3)).astype(np.uint8)
    r0, r1, c0, c1 = box
    rad = int(np.ceil(radius))
    for yy in range(r0, r1):
        for xx in range(c0, c1):
            for k in range(len(uv)):
                u, v = uv[k]
                if abs(xx - np.floor(u + 0.5)) > rad or abs(yy - np.floor(v + 0.5)) > rad:
                    continue  # outside the point's square window, as the kernel scans it
                d = np.float32((xx - u) ** 2 + (yy - v) ** 2)
                if d > radius * radius:
                    continue
                if d < best[yy, xx]:
                    best[yy, xx], owner[yy, xx], flag[yy, xx] = d, k, bits[k]
                elif d == best[yy, xx]:
                    flag[yy, xx] |= bits[k]
    return flag, owner, best


def test_patches_match_a_brute_force_nearest_point_rule_with_ties():
    # Points on half-pixel and integer positions create equidistant pixels, of both polarities.
    rng = np.random.default_rng(5)
    uv = np.r_[np.stack([rng.integers(0, W * 2, 60) / 2.0, rng.integers(0, H * 2, 60) / 2.0], 1), [[-2.0, 15.5], [30.0, 47.5]]]
    pol = rng.integers(-1, 2, len(uv)).astype(np.int8)
    box = (3, 45, 2, 60)
    a = AlignedTimeSurface(W, H)
    for _ in range(2):  # reused instance: the second compose must not see the first's patches
        a.compose(_surface(_events([1], [1], [1])), _points_at(uv), np.eye(4), K, pol, 3.0, box)
    flag, owner, _ = _nearest_point_reference(uv, pol, 3.0, box)
    assert np.array_equal(a.accept, flag)
    ev = _events(np.repeat(np.arange(W), H), np.tile(np.arange(H), W), np.ones(W * H, np.int8))
    _, point = a.classify(ev, 3.0)
    assert np.array_equal(point, owner[ev.y, ev.x])
    assert np.count_nonzero(flag == 3) > 0 and len(np.unique(flag)) == 4  # ties and all polarities occurred


def _composed_with_random_events(seed: int, n_events: int, defer_events: bool = False):
    """A surface composed for 30 random points of random polarity, with ``n_events`` random events, 70 % kept."""
    rng = np.random.default_rng(seed)
    uv = np.stack([rng.uniform(5, W - 5, 30), rng.uniform(5, H - 5, 30)], 1)
    pol = rng.integers(-1, 2, 30).astype(np.int8)
    ev = _events(rng.integers(0, W, n_events), rng.integers(0, H, n_events), rng.choice([-1, 1], n_events))
    keep = rng.random(n_events) < 0.7
    a = AlignedTimeSurface(W, H).compose(_surface(ev), _points_at(uv), np.eye(4), K, pol, 4.0, (4, 40, 6, 60), ev, keep,
                                         classify_radius_px=2.0, defer_events=defer_events)
    return a, ev, keep


def test_kept_events_are_labelled_in_the_compose_pass_exactly_as_classify_labels_them():
    a, ev, keep = _composed_with_random_events(5, 400)
    kept = ev[keep]
    judged = a.kept_labels(kept, 2.0)
    assert judged is not None
    assert all(np.array_equal(x, y) for x, y in zip(judged, a.classify(kept, 2.0)))
    assert (judged[0] >= 0).any() and (judged[0] == 0).any() and (judged[0] == -1).any()
    # Other events or another radius are not the compose pass's: classify them afresh.
    assert a.kept_labels(ev, 2.0) is None and a.kept_labels(kept, 3.0) is None


def test_batch_judgement_gives_the_kept_labels_and_each_points_majority_polarity_without_copying_the_events():
    from evpose.fusion.event_labels import observed_point_polarity

    a, ev, keep = _composed_with_random_events(7, 600)
    label, majority = a.batch_judgement(ev, keep, 2.0)
    ref_label, ref_point = a.classify(ev[keep], 2.0)
    assert np.array_equal(label, ref_label)
    assert np.array_equal(majority, observed_point_polarity(ref_point, ev[keep].p, 30))
    assert (majority == 1).any() and (majority == -1).any() and (majority == 0).any()
    # Another mask or radius is not the compose pass's batch.
    assert a.batch_judgement(ev, ~keep, 2.0) is None and a.batch_judgement(ev, keep, 3.0) is None


def test_a_deferred_event_pass_labels_and_counts_as_the_compose_pass_and_ignores_later_changes_to_keep():
    a, ev, keep = _composed_with_random_events(9, 500)
    d, _, mask = _composed_with_random_events(9, 500, defer_events=True)
    assert "events_polarity_judged" not in d.last_counts  # nothing labelled before it is asked for
    mask[:] = False  # the caller's mask may change meanwhile: the pass judges the batch as it was composed
    label, majority = d.batch_judgement(ev, keep, 2.0)
    ref_label, ref_majority = a.batch_judgement(ev, keep, 2.0)
    assert np.array_equal(label, ref_label) and np.array_equal(majority, ref_majority)
    assert d.last_counts == a.last_counts and a.last_counts["events_polarity_removed"] > 0


def test_a_point_whose_patch_shows_only_the_other_polarity_is_reopened_to_both():
    # Point 0 predicts ON and sees only a fresh OFF event (its prediction is contradicted); point 1 predicts ON and sees
    # a fresh ON and a fresh OFF event (not contradicted: keeps ON only); point 2 predicts OFF and sees nothing.
    s = SeparatedTimeSurface(TimeSurfaceConfig(eta_ms=10.0), W, H)
    s.update(_events([10, 30, 31], [10, 10, 10], [-1, 1, -1], t0=59_000))
    pts = _points_at([(10.0, 10.0), (30.5, 10.0), (50.0, 30.0)])
    pol = np.array([1, 1, -1], np.int8)
    plain = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 3.0, None, t_us=60_000)
    assert plain.last_of(0)[10, 10] == NEVER_US and plain.point_has_events.tolist() == [False, True, False]
    a = AlignedTimeSurface(W, H).compose(s, pts, np.eye(4), K, pol, 3.0, None, t_us=60_000, reopen_contradicted=True)
    assert a.last_counts["points_reopened"] == 1
    assert a.point_has_events.tolist() == [True, True, False]
    assert a.accept[10, 10] == 3 and a.last_of(0)[10, 10] == s.last_of(-1)[10, 10]
    assert a.accept[10, 31] == 1 and a.last_of(0)[10, 31] == NEVER_US  # point 1 still hides its OFF event
    assert pol.tolist() == [1, 1, -1]  # the caller's prediction is not modified
