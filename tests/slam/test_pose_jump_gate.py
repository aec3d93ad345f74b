"""The scale-free plausibility gate on camera moves (TrackingConfig.max_jump_depths): a PnP or local-BA pose several
scene depths from where the camera was is rejected; ordinary inter-MCI moves pass."""

import numpy as np

from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.geometry import pose_jump_depths
from evpose.slam.tracking_config import TrackingConfig
from tests.slam.test_bundle_adjustment import K, _map


def _pose(c):
    T = np.eye(4)
    T[:3, 3] = c
    return T


def _points(scale=1.0):
    rng = np.random.default_rng(0)
    return scale * np.c_[rng.uniform(-1, 1, 30), rng.uniform(-1, 1, 30), rng.uniform(0.8, 1.2, 30)]


def test_a_pose_far_beyond_the_scene_depth_is_many_depths_away():
    # The session-25 defect's numbers: map points about one unit in front of a camera at the origin, a pose 65 units away.
    last, guess = _pose([0, 0, 0]), _pose([0.002, 0, 0])
    gate = TrackingConfig().max_jump_depths
    assert pose_jump_depths(_pose([65.0, 5.0, -4.0]), (last, guess), _points()) > gate > 0
    assert pose_jump_depths(_pose([0.005, 0, 0.001]), (last, guess), _points()) < 0.01


def test_the_nearest_reference_counts_and_the_ratio_is_scale_free():
    # A bad prediction does not reject a pose next to the last one; scaling the whole map leaves the ratio unchanged.
    last, far_guess = _pose([0, 0, 0]), _pose([3.0, 0, 0])
    assert pose_jump_depths(_pose([0.01, 0, 0]), (last, far_guess), _points()) < 0.02
    a = pose_jump_depths(_pose([0.3, 0.1, 0]), (last,), _points())
    b = pose_jump_depths(_pose([30.0, 10.0, 0]), (_pose([0, 0, 0]),), _points(100.0))
    assert np.isclose(a, b)


def test_no_point_distance_gives_an_infinite_ratio_for_any_move():
    assert pose_jump_depths(_pose([1.0, 0, 0]), (_pose([0, 0, 0]),), np.zeros((0, 3))) == np.inf
    assert pose_jump_depths(_pose([0, 0, 0]), (_pose([0, 0, 0]),), np.zeros((0, 3))) == 0.0


def test_the_local_ba_leaves_the_map_alone_when_its_solution_moves_a_keyframe_too_far():
    # Keyframe 3 starts 3 units (about 0.7 median point depths) off: the BA pulls it back; with a gate of 0.5 depths
    # that move counts as a divergence and the map stays as it was.
    m, _, true_T = _map(seed=3)
    m.keyframes[3].T_wc[:3, 3] += [3.0, 0, 0]
    start = m.keyframes[3].T_wc.copy()
    pts = m.point_array().copy()
    local_bundle_adjustment(m, K, window=4, iterations=30, huber_px=2.0, n_fixed=2)
    assert np.linalg.norm(m.keyframes[3].T_wc[:3, 3] - start[:3, 3]) > 2.0
    m, _, _ = _map(seed=3)
    m.keyframes[3].T_wc[:3, 3] += [3.0, 0, 0]
    rep = local_bundle_adjustment(m, K, window=4, iterations=30, huber_px=2.0, n_fixed=2, max_jump_depths=0.5)
    assert np.array_equal(m.keyframes[3].T_wc, start)
    assert np.array_equal(m.point_array(), pts)
    assert rep.final_error == rep.initial_error
