"""A re-join's two-view keyframes count as coasted poses for the next coast's velocity (``rejoin_holds_velocity``)."""

from types import SimpleNamespace

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.coasting import camera_frame_velocity
from evpose.slam.inertial import InertialConfig
from evpose.slam.map_rejoin import RejoinCandidate
from evpose.slam.system_failures import VisualFailureHandling
from evpose.slam.system_initialisation import TwoViewInitialisation
from slam_synthetic import circle_pose


def _lost_map() -> SlamMap:
    """The circling camera's map up to 60 ms (metres), lost while coasting."""
    m = SlamMap(0)
    m.keyframes = [Keyframe(0, 0, circle_pose(0.0))]
    m.points[7] = MapPoint(7, np.array([0.5, 0.1, 2.0]), {0: np.zeros(2)})
    for k in range(13):
        m.add_pose(k * 5000, circle_pose(k * 0.005))
    return m


def _two_view(t0_us: int, t1_us: int) -> SlamMap:
    rel = invert_pose(circle_pose(t0_us / 1e6)) @ circle_pose(t1_us / 1e6)
    rel[:3, 3] /= np.linalg.norm(rel[:3, 3])  # a unit baseline, as a fresh two-view map has
    m = SlamMap(5, keyframes=[Keyframe(0, t0_us, np.eye(4)), Keyframe(1, t1_us, rel)])
    m.add_pose(t0_us, m.keyframes[0].T_wc)
    m.add_pose(t1_us, m.keyframes[1].T_wc)
    return m


class _Rejoining(TwoViewInitialisation, VisualFailureHandling):
    """Just enough of the SLAM system for ``_try_rejoin`` and ``_coast_velocity``."""

    def __init__(self, old: SlamMap, new: SlamMap, ic: InertialConfig):
        self.cfg = SimpleNamespace(inertial=ic)
        self.atlas = SimpleNamespace(maps=[old, new], active=old)
        self._rejoin = RejoinCandidate(old, camera_frame_velocity(old, 30_000))
        self._coast_hold = None

    def _gyro_rotation(self, t0_us, t1_us, T0):
        return circle_pose(t1_us / 1e6)[:3, :3]


def _rejoined(on: bool):
    old, new = _lost_map(), _two_view(300_000, 312_000)
    s = _Rejoining(old, new, InertialConfig(rejoin_holds_velocity=on))
    assert s._try_rejoin(new) is not None and s.atlas.maps == [old]
    # A PnP pose 20 ms after the two-view map lands 0.3 m off the circle: a re-localisation's correction, not motion.
    T = circle_pose(0.332).copy()
    T[:3, 3] += np.array([0.3, 0.0, 0.0])
    old.add_pose(332_000, T)
    return s, old


def test_the_rejoin_holds_the_velocity_that_placed_its_keyframes():
    s, old = _rejoined(True)
    assert s._coast_hold[0] == old.id and s._coast_hold[1] == 312_000
    v = s._coast_velocity(old)
    # The coasting's velocity (the circle's, in the camera frame), not the jump's.
    np.testing.assert_allclose(v, s._coast_hold[2])
    assert 0.9 < np.linalg.norm(v) * 1e6 / np.linalg.norm(camera_frame_velocity(_lost_map(), 30_000) * 1e6) < 1.1


def test_off_the_jump_after_the_rejoin_becomes_the_coasting_velocity():
    s, old = _rejoined(False)
    assert s._coast_hold is None
    v_true = np.linalg.norm(camera_frame_velocity(_lost_map(), 30_000))
    assert np.linalg.norm(s._coast_velocity(old)) > 5 * v_true
