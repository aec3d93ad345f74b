"""Event-inertial guards against maps that start wrong (:mod:`evpose.slam.inertial_guards`): a two-view start the gyro
contradicts is refused, and a map lost young is discarded from the atlas."""

from types import SimpleNamespace

import numpy as np
from scipy.spatial.transform import Rotation

import evpose.slam.system_initialisation as si
from evpose.slam.atlas import SlamMap
from evpose.slam.features import FrontendTracks
from evpose.slam.initialization_config import InitializationConfig
from evpose.slam.inertial import InertialConfig
from evpose.slam.inertial_guards import discard_map, two_view_gyro_disagreement_deg, young_lost_map
from evpose.slam.initialization import TwoViewResult
from evpose.slam.map_rejoin import RejoinCandidate
from evpose.slam.step_result import SlamStatus
from evpose.slam.system_failures import VisualFailureHandling
from tests.slam.test_atlas import _pose


def _rz(deg: float) -> np.ndarray:
    return Rotation.from_euler("z", deg, degrees=True).as_matrix()


def test_disagreement_is_the_angle_between_the_two_view_and_the_gyro_rotations():
    assert abs(two_view_gyro_disagreement_deg(_rz(10.0), _rz(2.0)) - 8.0) < 1e-9
    axis = Rotation.from_rotvec([0.0, np.radians(3.0), 0.0]).as_matrix()
    assert abs(two_view_gyro_disagreement_deg(axis, _rz(4.0)) - 5.0) < 0.01  # 3 deg about y against 4 about z
    assert two_view_gyro_disagreement_deg(_rz(10.0), None) == 0.0


def _map(span_s: float, initialised: bool = False) -> SlamMap:
    m = SlamMap(id=0, imu_initialised=initialised)
    for k in range(4):
        m.traj_t.append(int(k * span_s / 3 * 1e6))
        m.traj_T.append(_pose(np.zeros(3), (0.01 * k, 0.0, 0.0)))
        m.traj_ref.append(-1)
        m.traj_rel.append(np.eye(4))
    return m


def test_only_a_young_uninitialised_map_is_to_be_discarded():
    assert young_lost_map(_map(0.02), 0.1)
    assert not young_lost_map(_map(0.2), 0.1)
    assert not young_lost_map(_map(0.02, initialised=True), 0.1)
    assert not young_lost_map(_map(0.02), 0.0)
    assert not young_lost_map(SlamMap(id=1), 0.1)


def test_a_discarded_map_writes_no_trajectory_and_keeps_its_id():
    m = _map(0.02)
    discard_map(m, "starved")
    assert (m.id, m.traj_t, m.keyframes, m.points) == (0, [], [], {})
    assert "starved" in m.lost_reason


class _Losing(VisualFailureHandling):
    """Just enough of the SLAM system for ``_lose``."""

    def __init__(self, m: SlamMap, discard_s: float, rejoin=None):
        self.maps = [m]
        self.atlas = SimpleNamespace(active=m, new_map=lambda: self.maps.append(SlamMap(id=len(self.maps))))
        self.fe = SimpleNamespace(track_to_point={1: 2}, init_ref={})
        self.cfg = SimpleNamespace(inertial=InertialConfig(discard_lost_young_s=discard_s))
        self.imu, self._rejoin = object(), rejoin


def test_losing_a_young_map_discards_it_unless_it_may_be_rejoined():
    m = _map(0.02)
    status, _, _, _ = _Losing(m, 0.1)._lose("starved")
    assert status is SlamStatus.LOST and m.traj_t == []
    kept = _map(0.02)
    _Losing(kept, 0.0)._lose("starved")  # off
    assert len(kept.traj_t) == 4
    joinable = _map(0.02)
    _Losing(joinable, 0.1, RejoinCandidate(joinable, np.zeros(3)))._lose("starved")
    assert len(joinable.traj_t) == 4


class _Starting(si.TwoViewInitialisation):
    """Just enough of the SLAM system for ``_try_initialise`` to reach the gyro check."""

    def __init__(self, max_deg: float, gyro_deg: float):
        self.fe = FrontendTracks()
        self.fe.ids = np.arange(30, dtype=np.int64)
        self.fe.uv = np.zeros((30, 2), np.float32)
        self.fe.init_ref = {k: np.zeros(2) for k in range(30)}
        self.fe.init_ref_t = 0
        self._init_cfg = InitializationConfig(max_frames=5, min_matches=20)
        # The guard alone: a gyro-resolved start (init_gyro_two_view) is tests/slam/test_gyro_two_view_s37.py's.
        self.cfg = SimpleNamespace(inertial=InertialConfig(init_max_gyro_deg=max_deg, init_gyro_two_view=False), seed=0)
        self.K, self.imu = np.eye(3), object()
        self._gyro_deg = gyro_deg

    def _gyro_camera_delta(self, t0_us, t1_us):
        return _rz(self._gyro_deg)


def test_a_two_view_start_far_off_the_gyro_is_refused(monkeypatch):
    T = np.eye(4)
    T[:3, :3] = _rz(12.0)
    monkeypatch.setattr(si, "initialize_two_view", lambda *a, **k: TwoViewResult(True, T_wc2=T))
    mci = SimpleNamespace(t_us=20000, image8=None)
    status, reason, pose = _Starting(5.0, 1.0)._try_initialise(mci)
    assert status is SlamStatus.NOT_INITIALISED and pose is None
    assert "11.0 deg off the gyro" in reason


def _map_with_coasted_keyframes() -> SlamMap:
    """Keyframes 0-5 every 10 ms; 0, 1 and 3 were coasted and see no point, 2, 4 and 5 share two points."""
    from evpose.slam.atlas import Keyframe, MapPoint

    m = SlamMap(id=0)
    for k in range(6):
        m.keyframes.append(Keyframe(k, 10000 * k, _pose(np.zeros(3), (0.01 * k, 0.0, 0.0))))
    for pid in range(2):
        m.points[pid] = MapPoint(pid, np.array([0.0, 0.0, 2.0]), {k: np.zeros(2) for k in (2, 4, 5)})
    m.points[9] = MapPoint(9, np.array([0.0, 0.0, 2.0]), {1: np.zeros(2)})  # one observation: not in the BA
    return m


def test_the_ba_keyframes_are_those_seeing_a_point_with_two_observations():
    from evpose.slam.inertial_guards import bundle_keyframes

    m = _map_with_coasted_keyframes()
    assert [kf.id for kf in bundle_keyframes(m, m.keyframes, 6)] == [2, 4, 5]
    assert bundle_keyframes(m, m.keyframes, 0) == []


def test_the_window_starts_at_its_oldest_keyframe_the_ba_holds():
    from evpose.slam.inertial_guards import anchored_window

    m = _map_with_coasted_keyframes()
    assert anchored_window(m, 6) == 4  # keyframe 2 becomes the fixed one
    assert anchored_window(m, 3) == 2  # keyframe 3 sees nothing: keyframe 4 becomes the fixed one
    assert anchored_window(m, 2) == 2  # already starts at a held keyframe
    m.points.clear()
    assert anchored_window(m, 6) == 6  # nothing held: unchanged


def test_gyro_priors_chain_across_keyframes_the_ba_leaves_out():
    from evpose.core.imu import ImuSamples
    from evpose.slam.config import TrackingConfig
    from evpose.slam.system_gyro import GyroAids

    t = np.arange(0, 100001, 1000, dtype=np.int64)
    imu = ImuSamples(t, np.tile([0.0, 0.0, 9.81], (len(t), 1)), np.tile([0.0, 0.0, 1.0], (len(t), 1)))  # 1 rad/s about z
    m = _map_with_coasted_keyframes()

    def priors(chain: bool) -> dict:
        s = SimpleNamespace(imu=imu, calib=SimpleNamespace(T_cam_imu=np.eye(4), time_offset_us=0),
                            cfg=SimpleNamespace(inertial=InertialConfig(ba_gyro_prior_chain=chain), tracking=TrackingConfig(local_window=6)))
        return GyroAids._keyframe_rotation_priors(s, m)

    assert sorted(priors(False)) == [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5)]
    chained = priors(True)
    assert sorted(chained) == [(2, 4), (4, 5)]
    # Each prior is the gyro's turn over its pair: 20 ms at 1 rad/s across the coasted keyframe 3.
    assert abs(two_view_gyro_disagreement_deg(chained[(2, 4)], np.eye(3)) - np.degrees(0.02)) < 1e-6


class _MapMade(Exception):
    """Raised where a start that passed the gyro check goes on to make its map."""


def test_e_i_c3_never_refuses_a_two_view_start(monkeypatch):
    from evpose.slam.inertial import InertialConfiguration

    T = np.eye(4)
    T[:3, :3] = _rz(12.0)
    monkeypatch.setattr(si, "initialize_two_view", lambda *a, **k: TwoViewResult(True, T_wc2=T))

    def new_map():
        raise _MapMade

    for conf, refused in ((InertialConfiguration.C3, False), (InertialConfiguration.C2, True)):
        s = _Starting(5.0, 1.0)
        s.cfg.inertial.configuration = conf
        s.atlas = SimpleNamespace(active=None, new_map=new_map)
        try:
            status, _, _ = s._try_initialise(SimpleNamespace(t_us=20000, image8=None))
            made = False
        except _MapMade:
            made = True
        assert made is not refused
        if refused:
            assert status is SlamStatus.NOT_INITIALISED
