"""A re-join's scale from the scene depth (``InertialConfig.rejoin_scale_depth_weight``, :func:`depth_scale`)."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.coasting import camera_frame_velocity
from evpose.slam.map_rejoin import depth_scale, rejoin_similarity, scene_depth
from slam_synthetic import circle_pose, in_units, lost_circle_map

SCENE = np.array([[0.5, 0.1, 2.0], [-0.4, 0.3, 2.6], [0.2, -0.5, 3.1], [0.0, 0.2, 2.2], [-0.3, -0.2, 2.9]])
"""Points in front of the circling camera at t = 0 (camera frame, metres)."""


def _old_map(units: float, n_points: int = 5) -> SlamMap:
    """The circling camera's map up to 60 ms in units of ``units`` metres; its keyframe at t = 0 sees ``n_points``."""
    T = circle_pose(0.0)
    return lost_circle_map(units, {i: T[:3, :3] @ X + T[:3, 3] for i, X in enumerate(SCENE[:n_points])})


def _two_view_map(t0_us: int, t1_us: int, baseline: float, depth_units: float) -> SlamMap:
    """A two-view map at ``t0``/``t1`` whose kf1 is ``baseline`` units from kf0 and whose points see the scene (the same
    camera-frame depths as the old keyframe's) in units of ``depth_units`` metres: the two are independent, as a
    two-view start's baseline is when its translation direction is uncertain."""
    rel = invert_pose(circle_pose(t0_us / 1e6)) @ circle_pose(t1_us / 1e6)
    rel[:3, 3] *= baseline / np.linalg.norm(rel[:3, 3])
    m = SlamMap(5, keyframes=[Keyframe(0, t0_us, np.eye(4)), Keyframe(1, t1_us, rel)])
    for i, X in enumerate(SCENE):
        m.points[40 + i] = MapPoint(40 + i, X / depth_units, {0: np.zeros(2), 1: np.ones(2)}, created_kf=1)
    m.add_pose(t0_us, m.keyframes[0].T_wc)
    m.add_pose(t1_us, m.keyframes[1].T_wc)
    return m


def test_scene_depth_is_the_median_camera_depth_of_the_points_a_keyframe_sees():
    old = _old_map(0.5)
    assert np.isclose(scene_depth(old, old.keyframes[0], 5), np.median(SCENE[:, 2]) / 0.5)
    assert scene_depth(old, old.keyframes[0], 6) is None  # too few points


def test_the_depth_scale_matches_the_scene_depth_across_the_gap():
    old = _old_map(0.5)  # half-metre units
    new = _two_view_map(300_000, 330_000, baseline=1.0, depth_units=2.0)  # its points in two-metre units
    assert np.isclose(depth_scale(old, new, 5), 4.0)
    assert depth_scale(_old_map(0.5, n_points=3), new, 5) is None


def test_the_weight_blends_the_baseline_scale_and_the_depth_scale_geometrically():
    old = _old_map(0.5)
    v = camera_frame_velocity(old, 30_000)
    R0, R1 = circle_pose(0.3)[:3, :3], circle_pose(0.33)[:3, :3]
    # The two-view baseline says 1 new unit is 10 times the coasted 30 ms; the depth says 4 old units per new unit.
    true_baseline = np.linalg.norm(circle_pose(0.33)[:3, 3] - circle_pose(0.3)[:3, 3]) / 0.5
    new = _two_view_map(300_000, 330_000, baseline=0.1 * true_baseline, depth_units=2.0)
    s_base = rejoin_similarity(old, new, R0, R1, v)[2]
    assert 9.0 < s_base < 11.0  # coasting on the circle's velocity: within a few percent of 10
    assert np.isclose(rejoin_similarity(old, new, R0, R1, v, depth_weight=1.0, depth_min_points=5)[2], 4.0)
    assert np.isclose(rejoin_similarity(old, new, R0, R1, v, depth_weight=0.5, depth_min_points=5)[2], np.sqrt(4.0 * s_base))
    # Too few points on either side: the baseline's scale.
    assert rejoin_similarity(old, new, R0, R1, v, depth_weight=1.0, depth_min_points=6)[2] == s_base
