"""The pre-initialisation coast velocity of E-I-C2 is not read across a re-localisation (``coast_hold_velocity``)."""

from types import SimpleNamespace

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.inertial import InertialConfig
from evpose.slam.system_failures import VisualFailureHandling
from tests.slam.test_atlas import _pose as _T


def _pose(x: float) -> np.ndarray:
    return _T(np.zeros(3), (x, 0.0, 0.0))


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


class _Bridging(VisualFailureHandling):
    """Just enough of the SLAM system for ``_bridge_or_lose`` on a map the IMU initialisation has not reached."""

    def __init__(self, m: SlamMap, ic: InertialConfig):
        self.atlas = SimpleNamespace(active=m)
        self.fe = SimpleNamespace(ids=np.zeros(0, np.int64), uv=np.zeros((0, 2)), track_to_point={})
        self.cfg = SimpleNamespace(inertial=ic, tracking=SimpleNamespace(reprojection_threshold_px=2.5))
        self.imu, self.K, self._last_visual_t = object(), np.eye(3), m.traj_t[-1]
        self.keyframes = []

    def _new_keyframe(self, m, t_us, T_wc, img8=None, adjust=True, triangulate=True):
        self.keyframes.append((t_us, adjust, triangulate))
        return T_wc


def _coast_once(ic: InertialConfig):
    m = SlamMap(id=1)
    for k in range(10):
        m.traj_t.append(5000 * k)
        m.traj_T.append(_pose(0.005 * k))
    s = _Bridging(m, ic)
    mci = SimpleNamespace(t_us=50000, image8=None)
    status, _, T_wc, _ = s._bridge_or_lose(mci, "starved", R_prior=np.eye(3))
    return s, status, T_wc


def test_pre_initialisation_coast_keyframe_triangulates_only_when_asked():
    s, status, T_wc = _coast_once(InertialConfig(coast_triangulate=True))
    assert status.name == "INERTIAL" and s.keyframes == [(50000, False, True)]
    # Coasted on the trajectory's 1 unit/s for 5 ms.
    np.testing.assert_allclose(T_wc[0, 3], 0.05, atol=1e-9)
    s, _, _ = _coast_once(InertialConfig())  # off by default since session 36
    assert s.keyframes == [(50000, False, False)]
    # The coast is remembered for the next one (coast_hold_velocity).
    assert s._coast_hold[0] == 1 and s._coast_hold[1] == 50000
