"""A PnP step far off the map's own recent speed is refused (``TrackingConfig.speed_jump_ratio``)."""

from types import SimpleNamespace

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.config import SlamConfig
from evpose.slam.speed_jump import is_speed_jump, speed_jump
from evpose.slam.system import EventSlam
from tests.slam.test_atlas import _pose as _T


def _pose(x: float) -> np.ndarray:
    return _T(np.zeros(3), (x, 0.0, 0.0))


def _map() -> SlamMap:
    """Poses every 10 ms moving +1 unit/s along x for 100 ms."""
    m = SlamMap(id=0)
    for k in range(11):
        m.add_pose(10000 * k, _pose(0.01 * k))
    return m


def test_ratio_is_the_step_speed_over_the_recent_speed():
    m = _map()
    assert abs(speed_jump(m, 110000, _pose(0.11), 60000) - 1.0) < 1e-9
    # Five times the distance in the same time; the same distance in a fifth of the time.
    assert abs(speed_jump(m, 110000, _pose(0.15), 60000) - 5.0) < 1e-9
    assert abs(speed_jump(m, 102000, _pose(0.11), 60000) - 5.0) < 1e-9
    # A collapse: a tenth of the step.
    assert abs(speed_jump(m, 110000, _pose(0.101), 60000) - 0.1) < 1e-9


def test_no_ratio_without_a_long_enough_or_moving_trajectory():
    m = _map()
    assert speed_jump(m, 110000, _pose(0.11), 200000) is None  # trajectory shorter than the span
    assert speed_jump(m, 100000, _pose(0.11), 60000) is None  # no time since the last pose
    still = SlamMap(id=1)
    for k in range(11):
        still.add_pose(10000 * k, _pose(0.0))
    assert speed_jump(still, 110000, _pose(0.01), 60000) is None


def test_limits_each_side_and_off():
    assert is_speed_jump(4.5, 4.0) and not is_speed_jump(0.2, 4.0)  # the drop side off by default
    assert is_speed_jump(0.2, 4.0, 4.0) and is_speed_jump(0.2, 0.0, 4.0) and not is_speed_jump(4.5, 0.0, 4.0)
    assert not is_speed_jump(3.9, 4.0, 4.0) and not is_speed_jump(0.26, 4.0, 4.0) and not is_speed_jump(None, 4.0, 4.0)
    assert not is_speed_jump(50.0, 0.0) and not is_speed_jump(50.0, 1.0)


def test_system_refuses_only_with_the_option_on_and_event_only():
    m = _map()
    for ratio, imu, refused in ((0.0, None, False), (4.0, None, True), (4.0, object(), False)):
        cfg = SlamConfig()
        cfg.tracking.speed_jump_ratio = ratio
        sys_ = SimpleNamespace(cfg=cfg, imu=imu, _speed_refusals=0)
        why = EventSlam._speed_jump(sys_, m, 110000, _pose(0.16))
        assert (why is not None) == refused
        if refused:
            assert "6.00 times" in why
    cfg = SlamConfig()
    cfg.tracking.speed_jump_ratio = 4.0
    sys_ = SimpleNamespace(cfg=cfg, imu=None, _speed_refusals=0)
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.12)) is None  # twice the speed: kept
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.1001)) is None  # a collapse: the drop side is off
    cfg.tracking.speed_drop_ratio = 4.0
    assert "0.01 times" in EventSlam._speed_jump(sys_, m, 110000, _pose(0.1001))
    # A map younger than speed_jump_min_age_s (its first pose at 0) is not judged.
    cfg.tracking.speed_jump_min_age_s = 0.2
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.16)) is None


def test_refusals_in_a_row_are_limited():
    m = _map()
    cfg = SlamConfig()
    cfg.tracking.speed_jump_ratio = 4.0
    cfg.tracking.speed_jump_max_refusals = 1
    sys_ = SimpleNamespace(cfg=cfg, imu=None, _speed_refusals=0)
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.16)) is not None
    sys_._speed_refusals = 1  # one refused already: the next jumped pose is accepted
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.16)) is None
    cfg.tracking.speed_jump_max_refusals = 0  # no limit
    assert EventSlam._speed_jump(sys_, m, 110000, _pose(0.16)) is not None
