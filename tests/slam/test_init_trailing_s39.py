"""The IMU initialisation's trailing-window fallback (``InertialConfig.init_trailing_fallback``): a map whose older,
re-joined segment carries another scale is refused over all its keyframes; the newest ``init_min_span_s`` of them, on
one scale, initialise it at that scale."""

import numpy as np
import pytest

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.system import EventSlam
from slam_synthetic import make_recording


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=2.0, speed=1.0, seed=5, shake=0.08)


def _map_with_a_rejoined_segment(shaken, old_factor: float) -> SlamMap:
    """Keyframes every 0.1 s at 0.3 map units per metre; before 0.6 s (the older segment) the steps are ``old_factor``
    times larger, as after a re-join whose scale was off."""
    gt = shaken.ground_truth
    T = gt.matrices()
    j = 600
    m = SlamMap(0)
    for i, k in enumerate(range(0, 1900, 100)):
        P = T[k].copy()
        p = T[k][:3, 3]
        P[:3, 3] = 0.3 * p if k >= j else 0.3 * T[j][:3, 3] + 0.3 * old_factor * (p - T[j][:3, 3])
        m.keyframes.append(Keyframe(i, int(gt.t[k]), P))
    return m


def _slam(shaken, fallback: bool) -> EventSlam:
    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    cfg.inertial.init_trailing_fallback = fallback
    cfg.inertial.full_ba_after_init = False  # no points here: the alignment alone is under test
    return EventSlam(cfg, shaken.calibration, shaken.imu)


def test_one_scale_over_the_rejoined_segments_is_refused_and_the_newest_keyframes_initialise_the_map(shaken):
    m = _map_with_a_rejoined_segment(shaken, 8.0)
    off = _slam(shaken, False)
    off._try_imu_init(m)
    assert not m.imu_initialised and not off.last_imu_init.ok
    m = _map_with_a_rejoined_segment(shaken, 8.0)
    on = _slam(shaken, True)
    on._try_imu_init(m)
    assert m.imu_initialised, on.last_imu_init.reason
    assert m.scale == pytest.approx(1 / 0.3, rel=0.05)
    assert min(on.last_imu_init.used) >= 6  # only keyframes of the newest 1.2 s (from 0.6 s on)
    assert set(m.inertial.velocities) == {m.keyframes[k].id for k in on.last_imu_init.used}


def test_the_fallback_leaves_a_map_on_one_scale_as_it_was(shaken):
    a, b = _map_with_a_rejoined_segment(shaken, 1.0), _map_with_a_rejoined_segment(shaken, 1.0)
    _slam(shaken, False)._try_imu_init(a)
    _slam(shaken, True)._try_imu_init(b)
    assert a.imu_initialised and b.imu_initialised
    assert a.scale == b.scale
    assert all(np.array_equal(x.T_wc, y.T_wc) for x, y in zip(a.keyframes, b.keyframes))
