"""Re-joining a map lost while coasting (E-I-C2/C3, before the IMU initialisation) with the next two-view map."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.coasting import camera_frame_velocity
from evpose.slam.map_rejoin import merge_into, rejoin_similarity
from slam_synthetic import circle_pose, in_units, lost_circle_map


def _old_map(scale: float) -> SlamMap:
    """A map of the circling camera up to 60 ms, in units of ``1 / scale`` metres, with one keyframe and point."""
    return lost_circle_map(scale, {7: np.array([0.5, 0.1, 2.0])})


def _two_view_map(t0_us: int, t1_us: int, baseline: float) -> tuple[SlamMap, np.ndarray]:
    """The two-view map a fresh initialisation makes at ``t0``/``t1``: first keyframe at the origin, ``baseline`` units
    between them; returns it and a point of the scene (metres, world) expressed in it."""
    T0, T1 = circle_pose(t0_us / 1e6), circle_pose(t1_us / 1e6)
    rel = invert_pose(T0) @ T1
    d = np.linalg.norm(rel[:3, 3])
    rel[:3, 3] *= baseline / d
    X_world = np.array([2.5, 1.0, 0.3])
    X_new = (invert_pose(T0) @ np.r_[X_world, 1.0])[:3] * baseline / d
    m = SlamMap(5, keyframes=[Keyframe(0, t0_us, np.eye(4)), Keyframe(1, t1_us, rel)])
    m.points[40] = MapPoint(40, X_new, {0: np.zeros(2), 1: np.ones(2)}, created_kf=1)
    m.add_pose(t0_us, m.keyframes[0].T_wc)
    m.add_pose(t1_us, m.keyframes[1].T_wc)
    return m, X_world


def test_the_new_map_lands_where_the_lost_map_coasts_to_at_its_scale():
    scale = 4.0  # the lost map's units are a quarter metre
    old = _old_map(scale)
    v = camera_frame_velocity(old, 30_000)
    new, X_world = _two_view_map(300_000, 330_000, baseline=1.0)
    # The gyro's orientations at the two keyframes (exact here).
    R0, R1 = circle_pose(0.3)[:3, :3], circle_pose(0.33)[:3, :3]
    R, t, s = rejoin_similarity(old, new, R0, R1, v)
    first = merge_into(old, new, R, t, s)
    assert first == 1 and [k.id for k in old.keyframes] == [0, 1, 2]
    truth0, truth1 = in_units(circle_pose(0.3), scale), in_units(circle_pose(0.33), scale)
    # Coasting on the circle's camera-frame velocity places the keyframes within a few percent of the 0.24 m gap.
    gap = np.linalg.norm(truth0[:3, 3] - old.traj_T[12][:3, 3])
    assert np.linalg.norm(old.keyframes[1].T_wc[:3, 3] - truth0[:3, 3]) < 0.05 * gap
    assert np.linalg.norm(old.keyframes[2].T_wc[:3, 3] - truth1[:3, 3]) < 0.05 * gap
    assert np.allclose(old.keyframes[2].T_wc[:3, :3], truth1[:3, :3], atol=1e-9)
    # The new map's point follows its keyframes into the old frame and scale, its observations renumbered.
    p = old.points[40]
    assert np.linalg.norm(p.xyz - X_world / scale) < 0.05 * np.linalg.norm(X_world / scale - truth0[:3, 3])
    assert sorted(p.obs) == [1, 2] and p.created_kf == 2
    assert old.points[7].obs.keys() == {0}
    # One trajectory: the old poses, then the new map's, in time order; their keyframe references follow the renumbering.
    assert old.traj_t[-2:] == [300_000, 330_000] and old.traj_ref[-2:] == [2, 2]
    traj = old.trajectory().matrices()
    assert np.allclose(traj[-2], old.keyframes[1].T_wc) and np.allclose(traj[-1], old.keyframes[2].T_wc)
    assert old.segment_start_kf == 1


def test_a_map_that_coasts_nowhere_is_not_rejoined():
    old = _old_map(1.0)
    new, _ = _two_view_map(300_000, 330_000, baseline=1.0)
    assert rejoin_similarity(old, new, np.eye(3), np.eye(3), np.zeros(3)) is None
