"""The visual local BA's window at a re-joined segment's start (``InertialConfig.rejoin_scale_anchor``)."""

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.inertial import InertialConfig
from evpose.slam.inertial_guards import starts_at_rejoin


def _map(n: int, segment_start: int) -> SlamMap:
    m = SlamMap(0, keyframes=[Keyframe(k, 1000 * k, np.eye(4)) for k in range(n)])
    m.segment_start_kf = segment_start
    return m


def test_only_a_window_starting_at_a_rejoined_segment_is_anchored():
    m = _map(10, 7)  # keyframes 7, 8, 9 are the re-joined segment
    assert starts_at_rejoin(m, 3)
    # A window reaching past the segment start, or starting later (the segment has outgrown it): the scale is free.
    assert not starts_at_rejoin(m, 4) and not starts_at_rejoin(m, 2)
    # The map's first segment is a two-view start: its scale is arbitrary, nothing to hold.
    assert not starts_at_rejoin(_map(3, 0), 3)
    # Windows shorter than a pair or longer than the map hold nothing either.
    assert not starts_at_rejoin(_map(8, 7), 1) and not starts_at_rejoin(m, 11)


def test_the_velocity_hold_comes_with_the_anchor_and_the_depth_scale_is_off_by_default():
    # The hold alone let young re-joined segments' scale run away (session 38, seeds 13 / 29): never one without the other.
    cfg = InertialConfig()
    assert cfg.rejoin_holds_velocity and cfg.rejoin_scale_anchor == 0.01
    assert cfg.rejoin_scale_depth_weight == 0.0
