"""Event-only coasts written on the visual gyro (VisualGyroConfig.written_coasts): tracking coasts as before, the
written trajectory turns by the measured rotations (evpose.slam.written_coast)."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.slam import EventSlam, SlamConfig, SlamStatus
from evpose.slam import system_gyro
from evpose.slam.event_coasting import drop_unconfirmed_poses, event_only_coast_pose
from evpose.slam.written_coast import written_coast_pose, written_poses
from slam_synthetic import circle_map, make_recording


def _angle_deg(Ra, Rb):
    return np.degrees(Rotation.from_matrix(Ra.T @ Rb).magnitude())


def test_without_a_measurement_the_written_pose_is_the_coast():
    m = circle_map(12, 5000)
    t = m.traj_t[-1] + 5000
    T = written_coast_pose(m, t, 30_000, 5000, lambda dR0: None)
    np.testing.assert_allclose(T, event_only_coast_pose(m, t, 30_000), atol=1e-12)


def test_the_written_pose_turns_by_the_measured_rotation_from_the_written_previous_pose():
    m = circle_map(12, 5000)
    t_prev = m.traj_t[-1]
    # The previous MCI was written elsewhere than tracking placed it: the written pose chains from there.
    T_prev_written = m.traj_T[-1].copy()
    T_prev_written[:3, :3] = T_prev_written[:3, :3] @ Rotation.from_rotvec([0.0, 0.05, 0.0]).as_matrix()
    m.add_written_alternative(t_prev, T_prev_written)
    dR = Rotation.from_rotvec([0.0, 0.0, 0.01]).as_matrix()
    seen = []
    T = written_coast_pose(m, t_prev + 5000, 30_000, 5000, lambda dR0: (seen.append(dR0), dR)[1])
    np.testing.assert_allclose(T[:3, :3], T_prev_written[:3, :3] @ dR, atol=1e-12)
    # The search starts at the written poses' own rate over the step (the circle turns 0.75 rad/s).
    assert abs(_angle_deg(np.eye(3), seen[0]) - np.degrees(0.75 * 0.005)) < 0.05
    assert written_poses(m).traj_T[-1] is m.traj_alt[t_prev][0]


def test_a_young_map_writes_on_its_whole_trajectory_as_it_coasts():
    m = circle_map(3, 5000)  # 10 ms of trajectory, less than the span
    t = m.traj_t[-1] + 5000
    assert written_coast_pose(m, t, 30_000, 0, lambda dR0: None) is None
    np.testing.assert_allclose(written_coast_pose(m, t, 30_000, 5000, lambda dR0: None), event_only_coast_pose(m, t, 10_000), atol=1e-12)


def test_the_map_writes_the_alternative_and_keeps_it_through_transforms_and_drops():
    m = circle_map(10, 5000)
    t = m.traj_t[-1]
    T_alt = m.traj_T[-1].copy()
    T_alt[:3, 3] += [0.1, 0.0, 0.0]
    m.add_written_alternative(t, T_alt)
    m.add_written_alternative(t + 1, T_alt)  # not the newest pose's time: ignored
    assert set(m.traj_alt) == {t}
    np.testing.assert_allclose(m.trajectory().matrices()[-1], T_alt, atol=1e-12)
    np.testing.assert_allclose(m.trajectory(refit=False).matrices()[-1], m.traj_T[-1], atol=1e-12)  # tracking's own
    R = Rotation.from_rotvec([0.0, 0.0, 0.3]).as_matrix()
    m.transform(R, 2.0)
    np.testing.assert_allclose(m.traj_alt[t][0][:3, 3], 2.0 * R @ T_alt[:3, 3], atol=1e-12)
    assert drop_unconfirmed_poses(m, m.traj_t[-2]) == 1 and not m.traj_alt


@pytest.fixture(scope="module")
def early_map():
    return make_recording(duration_s=0.4, speed=1.5, seed=7, shake=0.08)


def _coast_twice(rec, monkeypatch, written: bool, max_map_s: float | None = None):
    cfg = SlamConfig()
    cfg.visual_gyro.written_coasts = written
    if max_map_s is not None:
        cfg.visual_gyro.written_coasts_max_map_s = max_map_s
    slam = EventSlam(cfg, rec.calibration)
    slam.step(rec.events)
    m = slam.atlas.active
    assert m is not None and len(m.traj_t) >= 3
    dR = Rotation.from_rotvec([0.0, 0.02, 0.0]).as_matrix()
    monkeypatch.setattr(system_gyro, "visual_rotation", lambda *a: dR)
    img = np.zeros((rec.calibration.height, rec.calibration.width), np.uint8)
    out = []
    for k in (1, 2):
        slam._prev_mci = (img, m.traj_t[-1])
        mci = SimpleNamespace(t_us=m.traj_t[-1] + 4000, image8=img)
        out.append(slam._bridge_or_lose(mci, "no tracks"))
    return m, out, dR


def test_coasting_tracks_as_without_it_and_writes_the_measured_turn(early_map, monkeypatch):
    m_off, out_off, _ = _coast_twice(early_map, monkeypatch, False)
    m_on, out_on, dR = _coast_twice(early_map, monkeypatch, True)
    assert [o[0] for o in out_on] == [o[0] for o in out_off] == [SlamStatus.COASTING] * 2
    for a, b in zip(out_on, out_off):
        np.testing.assert_array_equal(a[2], b[2])  # the pose tracking goes on from
    np.testing.assert_array_equal(np.stack(m_on.traj_T), np.stack(m_off.traj_T))
    assert not m_off.traj_alt and len(m_on.traj_alt) == 2
    t1, t2 = m_on.traj_t[-2], m_on.traj_t[-1]
    R0 = m_on.traj_T[-3][:3, :3]
    # Written: the last PnP pose turned by the measured rotation, twice; tracking coasted on its own rate.
    np.testing.assert_allclose(m_on.traj_alt[t1][0][:3, :3], R0 @ dR, atol=1e-9)
    np.testing.assert_allclose(m_on.traj_alt[t2][0][:3, :3], R0 @ dR @ dR, atol=1e-9)
    assert _angle_deg(m_on.traj_T[-1][:3, :3], R0 @ dR @ dR) > 0.1
    written = m_on.trajectory().matrices()
    np.testing.assert_allclose(written[-1][:3, :3], R0 @ dR @ dR, atol=1e-9)


def test_a_mature_map_writes_its_coast_as_tracked(early_map, monkeypatch):
    m, out, _ = _coast_twice(early_map, monkeypatch, True, max_map_s=0.01)
    assert [o[0] for o in out] == [SlamStatus.COASTING] * 2 and not m.traj_alt
    np.testing.assert_allclose(m.trajectory().matrices()[-2:], np.stack(m.traj_T[-2:]), atol=1e-9)
