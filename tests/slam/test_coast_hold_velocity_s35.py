"""The pre-initialisation coast velocity of E-I-C2 is not read across a re-localisation (``coast_hold_velocity``)."""

from types import SimpleNamespace

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.inertial import InertialConfig
from evpose.slam.system_failures import VisualFailureHandling


def _pose(x: float) -> np.ndarray:
    T = np.eye(4)
    T[0, 3] = x
    return T


def _map_after_jump() -> SlamMap:
    """Poses every 5 ms moving +1 unit/s along x; coasted up to 40 ms; a PnP pose at 45 ms jumped back by 0.5."""
    m = SlamMap(id=3)
    for k in range(10):
        m.traj_t.append(5000 * k)
        m.traj_T.append(_pose(0.005 * k))
    m.traj_t.append(45000)
    m.traj_T.append(_pose(0.045 - 0.5))
    return m


def _system(hold: bool, coast_hold):
    ic = InertialConfig(coast_hold_velocity=hold)
    sys_ = SimpleNamespace(cfg=SimpleNamespace(inertial=ic), _coast_hold=coast_hold)
    return sys_


def test_held_velocity_replaces_the_relocalisation_jump():
    m = _map_after_jump()
    held = np.array([1e-6, 0.0, 0.0])  # 1 unit/s in units per us
    v_on = VisualFailureHandling._coast_velocity(_system(True, (3, 40000, held)), m)
    v_off = VisualFailureHandling._coast_velocity(_system(False, (3, 40000, held)), m)
    np.testing.assert_allclose(v_on, held)
    # Without the hold the jump becomes the velocity: backwards along x, over ten times the true speed.
    assert v_off[0] < -10e-6


def test_trajectory_velocity_once_the_span_is_visual_or_another_map():
    m = _map_after_jump()
    held = np.array([1e-6, 0.0, 0.0])
    # The held velocity belongs to another map: read from the trajectory.
    v = VisualFailureHandling._coast_velocity(_system(True, (2, 40000, held)), m)
    assert v[0] < -10e-6
    # 40 ms of visual poses after the coast: the span no longer reaches a coasted pose.
    for k in range(1, 9):
        m.traj_t.append(45000 + 5000 * k)
        m.traj_T.append(_pose(0.045 - 0.5 + 0.002 * k))
    v = VisualFailureHandling._coast_velocity(_system(True, (3, 40000, held)), m)
    np.testing.assert_allclose(v, [0.4e-6, 0.0, 0.0], atol=1e-12)
