"""Event-only coasting through visual failures (TrackingConfig.coast_s) and its motion model."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.slam import EventSlam, SlamConfig, SlamStatus
from evpose.slam.event_coasting import camera_frame_rate, drop_past_blank, drop_unconfirmed_poses, event_only_coast_pose
from slam_synthetic import circle_map, circle_pose, make_recording


def test_coasting_holds_the_turn_rate_and_velocity_of_a_steady_turn():
    m = circle_map(12, 5000)
    w = camera_frame_rate(m, 30_000)
    assert abs(np.linalg.norm(w) * 1e6 - 1.2 / 1.6) < 1e-6  # rad/s of the circle
    t = m.traj_t[-1] + 60_000
    truth = circle_pose(t / 1e6)
    T = event_only_coast_pose(m, t, 30_000)
    assert np.degrees(Rotation.from_matrix(T[:3, :3].T @ truth[:3, :3]).magnitude()) < 1e-6
    step = np.linalg.norm(truth[:3, 3] - m.traj_T[-1][:3, 3])
    assert np.linalg.norm(T[:3, 3] - truth[:3, 3]) < 0.02 * step


def test_coasting_needs_enough_trajectory():
    m = circle_map(3, 5000)
    assert camera_frame_rate(m, 30_000) is None
    assert event_only_coast_pose(m, 20_000, 30_000) is None


def test_unconfirmed_poses_are_dropped_back_to_the_last_visual_one():
    m = circle_map(10, 5000)
    assert drop_unconfirmed_poses(m, 30_000) == 3
    assert m.traj_t[-1] == 30_000 and len(m.traj_T) == len(m.traj_ref) == len(m.traj_rel) == 7


@pytest.fixture(scope="module")
def early_map():
    return make_recording(duration_s=0.4, speed=1.5, seed=7, shake=0.08)


def _fail(rec, coast_s: float | None, after_us: int, drop: bool = False, blank_s: float = 0.0):
    cfg = SlamConfig()
    if coast_s is not None:
        cfg.tracking.coast_s = coast_s
    cfg.tracking.coast_drop_unconfirmed = drop
    cfg.tracking.coast_blank_s = blank_s
    slam = EventSlam(cfg, rec.calibration)
    slam.step(rec.events)
    m = slam.atlas.active
    assert m is not None and len(m.traj_t) >= 3
    mci = SimpleNamespace(t_us=m.traj_t[-1] + after_us, image8=np.zeros((rec.calibration.height, rec.calibration.width), np.uint8))
    return slam, m, slam._bridge_or_lose(mci, "no tracks")


def test_event_only_map_coasts_instead_of_opening_a_new_one_by_default(early_map):
    slam, m, (status, reason, pose, keyframe) = _fail(early_map, None, 8000)
    assert status is SlamStatus.COASTING and "coasted" in reason and pose is not None and keyframe
    assert slam.atlas.active is m and m.traj_t[-1] == m.keyframes[-1].t_us


def test_a_coast_longer_than_coast_s_loses_the_map_and_can_drop_its_unconfirmed_poses(early_map):
    for drop in (False, True):
        slam, m, _ = _fail(early_map, 0.4, 8000, drop)
        n = len(m.traj_t)
        mci = SimpleNamespace(t_us=m.traj_t[-1] + 500_000, image8=None)
        status, _, pose, _ = slam._bridge_or_lose(mci, "still no tracks")
        assert status is SlamStatus.LOST and pose is None and slam.atlas.active is not m
        assert len(m.traj_t) == (n - 1 if drop else n)



def test_a_blank_stretch_does_not_use_up_the_coast_when_coast_blank_s_allows(early_map):
    for blank_s, expected in ((0.0, SlamStatus.LOST), (0.3, SlamStatus.COASTING)):
        slam, m, _ = _fail(early_map, 0.4, 8000, blank_s=blank_s)
        # 0.5 s after the last visual pose, 0.25 s of it without an MCI because the event rate was below th_e.
        slam._blank_us = 250_000
        mci = SimpleNamespace(t_us=slam._last_visual_t + 500_000, image8=np.zeros((slam.height, slam.width), np.uint8))
        status, _, pose, _ = slam._bridge_or_lose(mci, "a blank wall")
        assert status is expected and (pose is None) == (expected is SlamStatus.LOST)


def test_a_young_map_coasts_on_its_whole_trajectory_when_coast_young_span_s_allows(early_map):
    for young_s, expected in ((0.0, SlamStatus.LOST), (0.05, SlamStatus.COASTING)):
        cfg = SlamConfig()
        cfg.tracking.coast_young_span_s = young_s
        cfg.tracking.coast_span_s = 0.2  # this recording's MCIs are ~0.1 s apart
        slam = EventSlam(cfg, early_map.calibration)
        slam.step(early_map.events)
        m = slam.atlas.active
        # Keep the map's two newest poses only: a two-view map one MCI old, too short for coast_span_s.
        for lst in (m.traj_t, m.traj_T, m.traj_ref, m.traj_rel):
            del lst[:-2]
        span_us = m.traj_t[-1] - m.traj_t[0]
        assert 50_000 <= span_us < cfg.tracking.coast_span_s * 1e6
        mci = SimpleNamespace(t_us=m.traj_t[-1] + 8000, image8=np.zeros((slam.height, slam.width), np.uint8))
        status, _, pose, _ = slam._bridge_or_lose(mci, "no tracks")
        assert status is expected and (slam.atlas.active is m) == (expected is SlamStatus.COASTING)


def test_a_coast_across_a_blank_ends_after_it_when_coast_after_blank_s_says_so(early_map):
    for after_s, expected in ((2.0, SlamStatus.COASTING), (0.0, SlamStatus.LOST)):
        slam, m, _ = _fail(early_map, 0.4, 8000, blank_s=0.3)
        slam.cfg.tracking.coast_after_blank_s = after_s
        img = np.zeros((slam.height, slam.width), np.uint8)
        # The first MCI past a 0.2 s blank coasts either way; the next one only while coast_after_blank_s allows.
        slam._blank_us, slam._after_blank_t = 200_000, slam._last_visual_t + 250_000
        first = slam._bridge_or_lose(SimpleNamespace(t_us=slam._after_blank_t, image8=img), "a blank wall")
        assert first[0] is SlamStatus.COASTING
        status, _, _, _ = slam._bridge_or_lose(SimpleNamespace(t_us=slam._after_blank_t + 10_000, image8=img), "still nothing")
        assert status is expected


def test_a_coasted_keyframe_triangulates_no_points_when_coast_triangulate_is_off(early_map, monkeypatch):
    from evpose.slam import system as slam_system

    for on in (True, False):
        calls = []
        real = slam_system.triangulate_new_points
        monkeypatch.setattr(slam_system, "triangulate_new_points", lambda *a, **k: calls.append(1) or real(*a, **k))
        cfg = SlamConfig()
        cfg.tracking.coast_triangulate = on
        slam = EventSlam(cfg, early_map.calibration)
        slam.step(early_map.events)
        m = slam.atlas.active
        n_kf, n_pts, calls[:] = len(m.keyframes), len(m.points), []
        mci = SimpleNamespace(t_us=m.traj_t[-1] + 8000, image8=np.zeros((slam.height, slam.width), np.uint8))
        status, _, _, keyframe = slam._bridge_or_lose(mci, "no tracks")
        # The keyframe is made either way (it records the tracks); only its triangulation is left out.
        assert status is SlamStatus.COASTING and keyframe and len(m.keyframes) == n_kf + 1
        assert bool(calls) == on and (on or len(m.points) <= n_pts)


def test_a_measured_orientation_replaces_the_coasted_one(early_map):
    # The visual gyro (evpose.slam.visual_gyro) hands the coast the orientation it measured for the MCI.
    slam, m, _ = _fail(early_map, None, 4000)
    R = m.traj_T[-1][:3, :3] @ Rotation.from_rotvec([0.0, 0.02, 0.0]).as_matrix()
    mci = SimpleNamespace(t_us=m.traj_t[-1] + 4000, image8=np.zeros((early_map.calibration.height, early_map.calibration.width), np.uint8))
    status, _, pose, _ = slam._bridge_or_lose(mci, "no tracks", R)
    assert status is SlamStatus.COASTING
    np.testing.assert_allclose(pose[:3, :3], R, atol=1e-12)


def _paste_patches(slam, m, T_wc: np.ndarray) -> np.ndarray:
    """An MCI showing each map point's template where ``T_wc`` projects it."""
    from evpose.core.trajectory import invert_pose
    from evpose.slam.geometry import project

    img = np.zeros((slam.height, slam.width), np.uint8)
    pts = [p for _, p in sorted(m.points.items()) if p.patch is not None]
    uv, z = project(slam.K, invert_pose(T_wc), np.stack([p.xyz for p in pts]))
    for p, (u, v), d in zip(pts, uv, z):
        r = p.patch.shape[0] // 2
        x, y = int(round(u)), int(round(v))
        if d > 0 and r <= x < slam.width - r and r <= y < slam.height - r:
            img[y - r:y + r + 1, x - r:x + r + 1] = np.maximum(img[y - r:y + r + 1, x - r:x + r + 1], p.patch)
    return img


def test_a_starved_map_is_edge_tracked_when_its_points_show_in_the_mci(early_map):
    from evpose.slam.event_coasting import event_only_coast_pose

    for enabled, expected in ((False, SlamStatus.COASTING), (True, SlamStatus.OK)):
        cfg = SlamConfig()
        cfg.edge_tracking.enabled = enabled
        slam = EventSlam(cfg, early_map.calibration)
        slam.step(early_map.events)
        m = slam.atlas.active
        t = m.traj_t[-1] + 4000
        T_pred = event_only_coast_pose(m, t, int(slam.cfg.tracking.coast_span_s * 1e6))
        mci = SimpleNamespace(t_us=t, image8=_paste_patches(slam, m, T_pred))
        status, reason, pose, _ = slam._bridge_or_lose(mci, "no tracks")
        assert status is expected, reason
        if enabled:
            assert reason.startswith("edge-tracked") and slam._last_visual_t == t and m.traj_t[-1] == t
            # The MCI agrees with the prediction, so the edges keep the pose there.
            assert np.degrees(Rotation.from_matrix(pose[:3, :3].T @ T_pred[:3, :3]).magnitude()) < 0.2


def test_edge_tracking_declines_a_blank_mci_and_the_map_coasts(early_map):
    slam, m, _ = _fail(early_map, None, 4000)
    slam.cfg.edge_tracking.enabled = True
    mci = SimpleNamespace(t_us=m.traj_t[-1] + 4000, image8=np.zeros((slam.height, slam.width), np.uint8))
    status, _, _, _ = slam._bridge_or_lose(mci, "no tracks")
    assert status is SlamStatus.COASTING


def test_poses_past_an_unconfirmed_blank_are_dropped_and_the_coast_before_it_kept():
    """``coast_drop_past_blank``: poses from the first MCI past the blank on go; the map's poses before it stay."""
    m = circle_map(10, 5000)  # poses at 0, 5, ..., 45 ms
    assert drop_past_blank(m, 35_000, 20_000) == 3
    assert m.traj_t[-1] == 30_000 and len(m.traj_T) == len(m.traj_ref) == len(m.traj_rel) == 7


def test_a_blank_crossed_before_the_last_visual_pose_drops_nothing():
    m = circle_map(10, 5000)
    assert drop_past_blank(m, 20_000, 30_000) == 0
    assert drop_past_blank(m, None, 30_000) == 0
    assert len(m.traj_t) == 10
