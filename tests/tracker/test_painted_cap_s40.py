"""The fused modes' cap on the painted points' share of registration (``map_refinement.fused_painted_max_share``):
the painted candidates are thinned by an even stride to the share, the others all kept; with the polarity filter
the dropped ones stay candidates (their ``T_align`` patches, the refiner) and are skipped by registration."""

from types import SimpleNamespace

import numpy as np

from evpose.tracker.config import TrackerConfig
from evpose.tracker.point_selection import capped_painted

N = 200
PAINTED = np.zeros(N, dtype=np.bool_)
PAINTED[100:160] = True  # 60 painted points among the map's 200


def fake(selector):
    return SimpleNamespace(_painted_mask=lambda: PAINTED, polarity_selector=selector)


def test_off_by_default():
    assert TrackerConfig().map_refinement.fused_painted_max_share == 0.0


def test_painted_points_are_thinned_to_the_share_without_the_polarity_filter():
    cand = np.arange(40, 160)  # 60 others, 60 painted
    out, skip = capped_painted(fake(None), cand, None, 0.2)
    assert skip is None
    assert np.array_equal(out[~PAINTED[out]], np.arange(40, 100))  # every other point kept
    kept = out[PAINTED[out]]
    assert kept.size == 15  # 0.2 / 0.8 x 60 others: 20 % of the 75 registered
    assert np.all(np.diff(kept) == 4)  # an even stride over the 60 painted candidates


def test_with_the_polarity_filter_the_dropped_painted_points_stay_candidates_and_are_skipped():
    cand = np.arange(40, 160)
    out, skip = capped_painted(fake(object()), cand, None, 0.2)
    assert np.array_equal(out, cand)
    assert skip.shape == (N,) and np.count_nonzero(skip) == 45 and np.all(PAINTED[skip])
    # An existing skip mask is extended, not overwritten.
    prior = np.zeros(N, dtype=np.bool_)
    prior[0] = True
    _, skip2 = capped_painted(fake(object()), cand, prior, 0.2)
    assert skip2[0] and np.count_nonzero(skip2) == 46 and not prior[100:160].any()


def test_nothing_changes_within_the_share():
    cand = np.arange(0, 120)  # 100 others, 20 painted: 17 %
    out, skip = capped_painted(fake(object()), cand, None, 0.2)
    assert out is cand and skip is None


def _fused_tracker(max_share: float):
    from test_fused_refiner_gain_s38 import _calibration
    from test_map_refinement import DOWN, painted_line

    from evpose.tracker.config import TrackerMode
    from evpose.tracker.modes import MotionComponents
    from evpose.tracker.tracker import Tracker

    cfg = TrackerConfig(mode=TrackerMode.FULL)
    cfg.map_refinement.fused_refine_max_share = max_share
    cfg.map_refinement.first_updates = 0
    cfg.edge_offsets.enabled = False
    tracker = Tracker(cfg, painted_line(0.02), _calibration(), components=MotionComponents(drives_pose=True))
    tracker._pose = DOWN.copy()
    return tracker


def test_the_fused_refiner_learns_only_while_the_painted_points_are_within_their_share_of_the_registered_points():
    from test_fused_refiner_gain_s38 import W
    from test_map_refinement import line_field

    from evpose.tracker.map_learning import learn_map_points
    from evpose.tracker.step_result import TrackStatus

    def moved(max_share: float, used: np.ndarray) -> int:
        tracker = _fused_tracker(max_share)
        counts: dict = {}
        learn_map_points(tracker, TrackStatus.OK, used, None, [line_field((W - 1) / 2)], None, None, counts, {})
        return counts.get("points_refined", 0)

    painted_map_points = np.arange(20)  # every point of the line is painted: a share of 1
    assert moved(0.0, painted_map_points) > 0  # off: always refined
    assert moved(0.5, painted_map_points) == 0  # the painted points alone: nothing anchors them
    assert moved(1.0, painted_map_points) > 0
