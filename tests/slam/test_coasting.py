"""Coasting through visual failures before the IMU initialisation (E-I-C2/C3), and the motion model it uses."""

import numpy as np
from types import SimpleNamespace

import pytest

from evpose.slam import EventSlam, SlamConfig, SlamMode, SlamStatus
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.coasting import camera_frame_velocity, coast_pose, constant_velocity_pose, drop_contradicted
from evpose.slam.inertial import InertialConfiguration
from slam_synthetic import circle_map, circle_pose, make_recording


def test_coasting_follows_a_steady_turn_with_the_camera_frame_velocity():
    m = circle_map(12, 5000)
    v = camera_frame_velocity(m, 30_000)
    t = m.traj_t[-1] + 60_000
    truth = circle_pose(t / 1e6)
    T = coast_pose(m, t, truth[:3, :3], v)
    err = np.linalg.norm(T[:3, 3] - truth[:3, 3])
    assert err < 0.02 * np.linalg.norm(truth[:3, 3] - m.traj_T[-1][:3, 3])
    straight = m.traj_T[-1][:3, 3] + m.traj_T[-1][:3, :3] @ v * 60_000  # the velocity not turned with the camera
    assert err < 0.5 * np.linalg.norm(straight - truth[:3, 3])


def test_constant_velocity_pose_extrapolates_the_last_step():
    m = circle_map(4, 5000)
    T = constant_velocity_pose(m, m.traj_t[-1] + 5000)
    assert np.linalg.norm(T[:3, 3] - circle_pose(0.02)[:3, 3]) < 1e-3
    assert np.array_equal(constant_velocity_pose(m, m.traj_t[-1] + 50_000), m.traj_T[-1])


def test_coasting_velocity_needs_enough_trajectory():
    m = circle_map(3, 5000)
    assert camera_frame_velocity(m, 30_000) is None
    assert camera_frame_velocity(SlamMap(0), 1000) is None


def test_predicted_pose_unlinks_the_tracks_it_contradicts():
    m = SlamMap(0, keyframes=[Keyframe(0, 0, np.eye(4))])
    K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])
    m.points = {0: MapPoint(0, np.array([0.0, 0.0, 4.0]), track_id=10), 1: MapPoint(1, np.array([0.5, 0.0, 4.0]), track_id=11)}
    ids = np.array([10, 11])
    uv = np.array([[120.0, 90.0], [120.0 + 25.0 + 30.0, 90.0]], np.float32)  # the second track jumped 30 px
    links = {10: 0, 11: 1}
    assert drop_contradicted(m, K, np.eye(4), ids, uv, links, 5.0) == 1
    assert links == {10: 0}


@pytest.fixture(scope="module")
def early_map():
    """0.4 s of a C2 run: one map, far from the IMU initialisation (1.2 s of keyframes)."""
    return make_recording(duration_s=0.4, speed=1.5, seed=7, shake=0.08)


def _c2(coast_s: float) -> SlamConfig:
    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    cfg.inertial.configuration = InertialConfiguration.C2
    cfg.inertial.coast_s = coast_s
    return cfg


def _fail_next_mci(rec, coast_s: float):
    slam = EventSlam(_c2(coast_s), rec.calibration, rec.imu)
    slam.step(rec.events)
    m = slam.atlas.active
    assert m is not None and m.traj_t and not m.imu_initialised
    t = m.traj_t[-1] + 8000
    mci = SimpleNamespace(t_us=t, image8=np.zeros((rec.calibration.height, rec.calibration.width), np.uint8))
    R = slam._gyro_rotation(m.traj_t[-1], t, m.traj_T[-1])
    return slam, m, slam._bridge_or_lose(mci, "no tracks", R)


def test_c2_coasts_a_map_without_imu_initialisation_instead_of_opening_a_new_one(early_map):
    slam, m, (status, reason, pose, keyframe) = _fail_next_mci(early_map, 0.4)
    assert status is SlamStatus.INERTIAL and "coasted" in reason and pose is not None and keyframe
    assert slam.atlas.active is m and m.traj_t[-1] == m.keyframes[-1].t_us
    _, m0, (status0, _, pose0, _) = _fail_next_mci(early_map, 0.0)
    assert status0 is SlamStatus.LOST and pose0 is None and m0.lost_reason == "no tracks"


def test_event_only_mode_never_coasts_on_the_gyro(early_map):
    # Event-only maps coast on their own motion (TrackingConfig.coast_s, tests/slam/test_event_coasting.py), never on
    # a gyro rotation, and without that coasting they are lost.
    cfg = SlamConfig()
    cfg.tracking.coast_s = 0.0
    slam = EventSlam(cfg, early_map.calibration)
    slam.step(early_map.events)
    m = slam.atlas.active
    mci = SimpleNamespace(t_us=m.traj_t[-1] + 8000, image8=None)
    assert slam._bridge_or_lose(mci, "no tracks", np.eye(3))[0] is SlamStatus.LOST
