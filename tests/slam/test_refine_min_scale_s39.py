"""InertialConfig.refine_min_scale: a scale refinement that would shrink a metric map below that share is refused."""
import numpy as np
import pytest

from evpose.slam import SlamConfig, SlamMode
from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.inertial_ba import InertialState
from evpose.slam.system import EventSlam
from slam_synthetic import make_recording


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=2.0, speed=1.0, seed=5, shake=0.08)


def _map_scaled(shaken, factor: float) -> tuple[SlamMap, np.ndarray]:
    T = shaken.ground_truth.matrices()
    m = SlamMap(0)
    for i, k in enumerate(range(0, 1900, 100)):
        P = T[k].copy()
        P[:3, 3] *= factor  # the first initialisation left the map this many times too large
        m.keyframes.append(Keyframe(i, int(shaken.ground_truth.t[k]), P))
    m.imu_initialised, m.imu_init_t_us = True, m.keyframes[0].t_us
    m.inertial = InertialState({}, np.zeros(3), np.zeros(3))
    return m, T


def _refine(shaken, factor: float, min_scale: float):
    m, T = _map_scaled(shaken, factor)
    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    cfg.inertial.refine_min_scale = min_scale
    slam = EventSlam(cfg, shaken.calibration, shaken.imu)
    before = [k.T_wc.copy() for k in m.keyframes]
    slam._refine_scale(m)
    return slam.last_scale_refinement, m, before


def test_a_refinement_shrinking_the_map_more_than_allowed_is_refused_and_leaves_the_map(shaken):
    # The map is 5 times too large: the (here correct) refinement would shrink it to 0.2 of its size.
    res, m, before = _refine(shaken, 5.0, 0.33)
    assert not res.ok and "shrinks the map" in res.reason
    assert m.scale_refined  # once only, as a refused alignment
    assert all(np.array_equal(k.T_wc, b) for k, b in zip(m.keyframes, before))
    assert m.scale == 1.0


def test_without_the_test_the_same_refinement_is_applied(shaken):
    res, m, _ = _refine(shaken, 5.0, 0.0)
    assert res.ok and res.scale == pytest.approx(0.2, rel=0.02)
    assert m.scale == pytest.approx(0.2, rel=0.02)


def test_a_refinement_within_the_allowed_shrink_is_applied(shaken):
    res, m, _ = _refine(shaken, 1.4, 0.33)
    assert res.ok and m.scale == pytest.approx(1 / 1.4, rel=0.02)
