"""Refined trajectories may place the PnP-placed MCIs between two keyframes on the keyframes' interpolated pose
(TrackingConfig.refit_keyframe_interpolation, on by default)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Atlas, Keyframe, MapPoint
from evpose.slam.config import SlamConfig
from evpose.slam.geometry import project
from evpose.slam.pose_refit import keyframe_interpolated
from slam_pose_scene import K, scene
from slam_pose_scene import pose as _pose
from tests.slam.test_atlas import _pose as _T


def test_a_placed_pose_between_keyframes_lands_on_their_interpolation():
    Ta, Tb = _T([0, 0, 0], [0, 0, 0]), _T([0, 0.2, 0], [1.0, 0, 0])
    odd = _T([0.1, 0, 0], [5.0, 5.0, 5.0])
    out = keyframe_interpolated([0, 25, 100], [Ta, odd, Tb], {25}, [0, 100], [Ta, Tb])
    assert np.allclose(out[1][:3, 3], [0.25, 0, 0])
    assert np.allclose(Rotation.from_matrix(out[1][:3, :3]).as_rotvec(), [0, 0.05, 0])
    assert np.allclose(out[0], Ta) and np.allclose(out[2], Tb)


def test_unplaced_keyframe_and_out_of_span_poses_are_kept():
    Ta, Tb = _T([0, 0, 0], [0, 0, 0]), _T([0, 0.2, 0], [1.0, 0, 0])
    coasted, kf_mci, late = _T([0, 0, 0.1], [3, 0, 0]), _T([0.3, 0, 0], [0, 2, 0]), _T([0, 0, 0], [9, 9, 9])
    # 50: not PnP-placed (a coast); 100: a keyframe MCI (keeps its own pose); 150: after the last keyframe
    out = keyframe_interpolated([0, 50, 100, 150], [Ta, coasted, kf_mci, late], {50, 100, 150} - {50}, [0, 100], [Ta, Tb])
    assert np.allclose(out[1], coasted) and np.allclose(out[2], kf_mci) and np.allclose(out[3], late)
    # one keyframe: nothing to interpolate between
    assert all(np.allclose(a, b) for a, b in zip(keyframe_interpolated([0, 50], [Ta, coasted], {50}, [0], [Ta]), [Ta, coasted]))


def test_a_keyframe_mci_s_own_pose_anchors_the_interpolation_over_the_keyframe_pose():
    Ta, Tb = _T([0, 0, 0], [0, 0, 0]), _T([0, 0, 0], [1.0, 0, 0])
    resolved_b = _T([0, 0, 0], [2.0, 0, 0])  # the keyframe MCI at t = 100, re-solved on the final points
    out = keyframe_interpolated([0, 50, 100], [Ta, np.eye(4), resolved_b], {50, 100}, [0, 100], [Ta, Tb])
    assert np.allclose(out[1][:3, 3], [1.0, 0, 0])  # half-way to the re-solved pose, not to the keyframe's 0.5
    assert np.allclose(out[2], resolved_b)


def test_keyframes_out_of_time_order_are_sorted_first():
    Ta, Tb, Tc = _T([0, 0, 0], [0, 0, 0]), _T([0, 0, 0], [1.0, 0, 0]), _T([0, 0, 0], [3.0, 0, 0])
    out = keyframe_interpolated([150], [np.eye(4)], {150}, [200, 0, 100], [Tc, Ta, Tb])
    assert np.allclose(out[0][:3, 3], [2.0, 0, 0])


def _map(interpolate: bool):
    """Keyframes at t = 0 and 100 on the true path; an MCI at t = 50 PnP-placed on pixels 3 px off its true pose."""
    X = scene(30, 0)
    Ta, Tb = _pose([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]), _pose([0.0, 0.02, 0.0], [0.2, 0.0, 0.0])
    truth = _pose([0.0, 0.01, 0.0], [0.1, 0.0, 0.0])
    uv, _ = project(K, invert_pose(truth), X)
    uv = uv + np.random.default_rng(1).normal(0, 3.0, uv.shape)
    m = Atlas(refit_K=K, interpolate_between_keyframes=interpolate).new_map()
    m.keyframes.append(Keyframe(0, 0, Ta))
    for i, x in enumerate(X):
        m.points[i] = MapPoint(i, x.copy())
    m.add_pose(0, Ta)
    m.add_pose(50, truth)
    m.record_pose_observations(50, np.arange(len(X)), uv, np.zeros(0, np.int64), np.zeros((0, 2)))
    m.keyframes.append(Keyframe(1, 100, Tb))
    m.add_pose(100, Tb)
    return m, truth


def test_the_map_option_replaces_the_re_solved_pose_only_when_set():
    m_off, truth = _map(False)
    m_on, _ = _map(True)
    off, on = m_off.trajectory().matrices()[1], m_on.trajectory().matrices()[1]
    assert not np.allclose(off, truth, atol=1e-4)  # re-solved on noisy pixels
    assert np.allclose(on, truth, atol=1e-9)  # the true path is linear between the keyframes here
    assert np.allclose(m_on.trajectory(refit=False).matrices()[1], m_off.trajectory(refit=False).matrices()[1])


def test_the_option_is_on_by_default_and_reaches_every_new_map():
    from evpose.core.camera import CameraCalibration
    from evpose.slam.system import EventSlam

    cal = CameraCalibration(240, 180, 200, 200, 119.5, 89.5)
    assert SlamConfig().tracking.refit_keyframe_interpolation is True
    assert EventSlam(SlamConfig(), cal).atlas.new_map().interpolate_between_keyframes is True
    cfg = SlamConfig()
    cfg.tracking.refit_keyframe_interpolation = False
    assert EventSlam(cfg, cal).atlas.new_map().interpolate_between_keyframes is False
