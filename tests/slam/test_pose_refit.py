"""Refined trajectories re-solve PnP-placed poses on where the map holds their inlier points at the end."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Atlas, Keyframe, MapPoint
from evpose.slam.geometry import project
from slam_pose_scene import K, scene
from slam_pose_scene import pose as _pose


def _scene(n=30, seed=0):
    return scene(n, seed)


def _map_with_one_tracked_pose(refit: bool):
    """A map whose pose at t = 10 was solved online 5 cm and 1 deg off, with pixels of its points seen from the truth."""
    X = _scene()
    truth = _pose([0.0, 0.02, 0.0], [0.2, 0.0, 0.0])
    uv, _ = project(K, invert_pose(truth), X)
    m = Atlas(refit_K=K if refit else None).new_map()
    m.keyframes.append(Keyframe(0, 0, np.eye(4)))
    for i, x in enumerate(X):
        m.points[i] = MapPoint(i, x.copy())
    m.add_pose(0, np.eye(4))
    m.add_pose(10, _pose([0.0, 0.02 + np.radians(1.0), 0.0], [0.25, 0.0, 0.0]))
    m.record_pose_observations(10, np.arange(len(X)), uv, np.zeros(0, np.int64), np.zeros((0, 2)))
    return m, truth


def test_a_tracked_pose_is_re_solved_on_its_inliers():
    m, truth = _map_with_one_tracked_pose(refit=True)
    out = m.trajectory().matrices()
    assert np.allclose(out[1], truth, atol=1e-6)
    assert np.allclose(out[0], np.eye(4))  # no recorded inliers (the initialisation's pose): as composed
    assert not np.allclose(m.trajectory(refined=False).matrices()[1], truth, atol=1e-3)  # online poses stay as solved


def test_a_caller_can_leave_the_re_solve_out_and_get_the_composed_pose():
    m, truth = _map_with_one_tracked_pose(refit=True)
    composed = _pose([0.0, 0.02 + np.radians(1.0), 0.0], [0.25, 0.0, 0.0])
    assert np.allclose(m.trajectory(refit=False).matrices()[1], composed)
    assert np.allclose(m.trajectory().matrices()[1], truth, atol=1e-6)  # the recorded observations are kept


def test_without_refit_nothing_is_recorded_and_the_pose_rides_on_its_keyframe():
    m, truth = _map_with_one_tracked_pose(refit=False)
    assert not m.traj_obs
    assert np.allclose(m.trajectory().matrices()[1], _pose([0.0, 0.02 + np.radians(1.0), 0.0], [0.25, 0.0, 0.0]))


def test_a_pose_whose_points_were_culled_keeps_its_composed_pose():
    m, truth = _map_with_one_tracked_pose(refit=True)
    for pid in range(5, 30):
        del m.points[pid]  # five left: too few to re-solve on
    assert np.allclose(m.trajectory().matrices()[1], _pose([0.0, 0.02 + np.radians(1.0), 0.0], [0.25, 0.0, 0.0]))


def test_tracks_that_got_a_point_later_join_the_refit_and_far_ones_do_not():
    X = _scene(31, seed=1)
    truth = _pose([0.0, 0.02, 0.0], [0.2, 0.0, 0.0])
    uv, _ = project(K, invert_pose(truth), X)
    noisy = uv + np.random.default_rng(3).normal(0, 1.0, uv.shape)
    guess = _pose([0.0, 0.03, 0.0], [0.25, 0.0, 0.0])
    errs = []
    for with_tracks in (False, True):
        m = Atlas(refit_K=K, refit_threshold_px=2.5).new_map()
        m.keyframes.append(Keyframe(0, 0, np.eye(4)))
        for i, x in enumerate(X):
            m.points[i] = MapPoint(i, x.copy(), track_id=100 + i)  # points 6-30 triangulated after the pose, on its tracks
        m.add_pose(10, guess)
        other = np.arange(106, 131) if with_tracks else np.zeros(0, np.int64)
        track_uv = uv[6:].copy()
        track_uv[-1] += 40.0  # a track that slid off its point: beyond the threshold, left out
        m.record_pose_observations(10, np.arange(6), noisy[:6], other, track_uv if with_tracks else np.zeros((0, 2)))
        errs.append(np.linalg.norm(m.trajectory().matrices()[0][:3, 3] - truth[:3, 3]))
    assert errs[1] < 0.3 * errs[0]
