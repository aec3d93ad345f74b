"""Keyframe decision of the local mapping (evpose/slam/local_map.py)."""

import numpy as np

from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import TrackingConfig
from evpose.slam.local_map import need_keyframe


def _map_with_last_keyframe_seeing(n_points: int) -> tuple[SlamMap, np.ndarray, np.ndarray]:
    """A map whose last keyframe observes ``n_points`` point tracks; the current tracks sit where the keyframe saw them."""
    m = SlamMap(0)
    uv = np.c_[np.linspace(20, 200, n_points), np.linspace(20, 160, n_points)]
    m.keyframes.append(Keyframe(0, 0, np.eye(4), {t: uv[t].copy() for t in range(n_points)}))
    for t in range(n_points):
        m.points[t] = MapPoint(t, np.array([0.0, 0.0, 5.0]), {0: uv[t].copy()}, track_id=t)
    return m, np.arange(n_points, dtype=np.int64), uv


def test_need_keyframe_when_tracked_points_fall_below_the_ratio_of_the_last_keyframe():
    m, ids, uv = _map_with_last_keyframe_seeing(20)
    # No key-point motion: only the tracked share decides (12 of 20 = 60 %).
    assert need_keyframe(m, ids, uv, 12, TrackingConfig(keyframe_tracked_ratio=0.7))
    assert not need_keyframe(m, ids, uv, 12, TrackingConfig(keyframe_tracked_ratio=0.5))


def test_need_keyframe_when_key_points_moved_far_from_the_last_keyframe():
    m, ids, uv = _map_with_last_keyframe_seeing(20)
    cfg = TrackingConfig(keyframe_tracked_ratio=0.5, keyframe_displacement_px=20.0)
    assert not need_keyframe(m, ids, uv + 10.0, 20, cfg)  # 14 px
    assert need_keyframe(m, ids, uv + 15.0, 20, cfg)  # 21 px


def _two_keyframes(baseline: float, seed: int = 0):
    """Keyframe 0 at the origin and keyframe 1 moved sideways by ``baseline``, both looking at points 5 m ahead: 30 map points
    both see (tracks 0-29) and 30 tracks without a point yet (100-129), observed without noise."""
    from evpose.core.trajectory import invert_pose
    from evpose.slam.geometry import project

    K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2, 2, 60), rng.uniform(-1.5, 1.5, 60), rng.uniform(4.5, 5.5, 60)]
    T1 = np.eye(4)
    T1[0, 3] = baseline
    uv0, _ = project(K, np.eye(4), X)
    uv1, _ = project(K, invert_pose(T1), X)
    tids = list(range(30)) + list(range(100, 130))
    m = SlamMap(0)
    m.keyframes = [Keyframe(0, 0, np.eye(4), {t: uv0[i] for i, t in enumerate(tids)}),
                   Keyframe(1, 100_000, T1, {t: uv1[i] for i, t in enumerate(tids)})]
    track_to_point = {}
    for i in range(30):
        m.points[i] = MapPoint(i, X[i].copy(), {0: uv0[i], 1: uv1[i]}, track_id=i)
        track_to_point[i] = i
    return m, K, track_to_point


def test_a_keyframe_pair_with_too_short_a_baseline_for_the_scene_depth_triangulates_nothing():
    from evpose.slam.local_map import triangulate_new_points

    # 0.13 m at 5 m: 1.5 deg, above the per-point parallax threshold of 1 deg and below the pair threshold of 2 deg.
    m, K, t2p = _two_keyframes(0.13)
    cfg = TrackingConfig(min_triangulation_deg=1.0, min_pair_parallax_deg=2.0)
    assert triangulate_new_points(m, K, m.keyframes[1], t2p, cfg, 1000) == 1000 and len(m.points) == 30
    m, K, t2p = _two_keyframes(0.13)
    assert triangulate_new_points(m, K, m.keyframes[1], t2p, TrackingConfig(min_triangulation_deg=1.0, min_pair_parallax_deg=0.0), 1000) > 1000
    # A wide enough pair (0.3 m: 3.4 deg) triangulates the new tracks where they are.
    m, K, t2p = _two_keyframes(0.3)
    nxt = triangulate_new_points(m, K, m.keyframes[1], t2p, cfg, 1000)
    assert nxt - 1000 >= 25
    assert all(t2p[t] >= 1000 for t in range(100, 130) if t in t2p)


def add_third_keyframe(m, K, x2: float, observe_points: bool = True) -> None:
    """Appends keyframe 2 of :func:`_two_keyframes`' map, ``x2`` m sideways, seeing its 60 tracks without noise; with
    ``observe_points`` the 30 map points get that observation too."""
    from evpose.core.trajectory import invert_pose
    from evpose.slam.geometry import project

    rng = np.random.default_rng(0)
    X = np.c_[rng.uniform(-2, 2, 60), rng.uniform(-1.5, 1.5, 60), rng.uniform(4.5, 5.5, 60)]
    T2 = np.eye(4)
    T2[0, 3] = x2
    uv2, _ = project(K, invert_pose(T2), X)
    tids = list(range(30)) + list(range(100, 130))
    m.keyframes.append(Keyframe(2, 200_000, T2, {t: uv2[i] for i, t in enumerate(tids)}))
    if observe_points:
        for i in range(30):
            m.points[i].obs[2] = uv2[i]


def test_a_new_point_keeps_its_tracks_observations_in_the_keyframes_between_the_pair_it_is_triangulated_from():
    from evpose.slam.local_map import triangulate_new_points

    # Keyframes 0, 1, 2 at 0, 0.1 and 0.3 m sideways, points 5 m ahead: the pair (0, 1) is too short for new points
    # (1.1 deg < 2 deg), so tracks 100-129 are triangulated from (0, 2); keyframe 1 saw them too.
    m, K, t2p = _two_keyframes(0.1)
    add_third_keyframe(m, K, 0.3)
    cfg = TrackingConfig(min_triangulation_deg=1.0, min_pair_parallax_deg=2.0, intermediate_observations=True)
    nxt = triangulate_new_points(m, K, m.keyframes[2], t2p, cfg, 1000)
    new = [m.points[p] for p in range(1000, nxt)]
    assert len(new) >= 25
    assert all(sorted(p.obs) == [0, 1, 2] for p in new)
    # A track whose view in keyframe 1 is off by 20 px is not given that observation.
    m, K, t2p = _two_keyframes(0.1)
    add_third_keyframe(m, K, 0.3, observe_points=False)
    m.keyframes[1].obs[100] = m.keyframes[1].obs[100] + 20.0
    nxt = triangulate_new_points(m, K, m.keyframes[2], t2p, cfg, 1000)
    p100 = m.points[t2p[100]]
    assert sorted(p100.obs) == [0, 2]
    # Off: only the pair observes a new point.
    m, K, t2p = _two_keyframes(0.1)
    add_third_keyframe(m, K, 0.3, observe_points=False)
    nxt = triangulate_new_points(m, K, m.keyframes[2], t2p, TrackingConfig(min_pair_parallax_deg=2.0, intermediate_observations=False), 1000)
    assert all(sorted(m.points[p].obs) == [0, 2] for p in range(1000, nxt))


def _map_with_keyframes(n: int, segment_start: int = 0) -> SlamMap:
    m = SlamMap(0, segment_start_kf=segment_start)
    m.keyframes = [Keyframe(i, 1000 * i, np.eye(4)) for i in range(n)]
    return m


def test_event_only_ba_window_reaches_past_the_local_window_and_event_inertial_keeps_it():
    from evpose.slam.local_map import visual_ba_window

    cfg = TrackingConfig(local_window=6, ba_window=10, ba_fixed_keyframes=2)
    assert visual_ba_window(_map_with_keyframes(12), cfg, event_only=True) == (10, 2)
    # Fewer keyframes than the window: all of them, one fixed (with the scale anchor).
    assert visual_ba_window(_map_with_keyframes(8), cfg, event_only=True) == (8, 1)
    assert visual_ba_window(_map_with_keyframes(12), cfg, event_only=False) == (6, 1)
    # 0 falls back to the local window.
    assert visual_ba_window(_map_with_keyframes(12), TrackingConfig(local_window=6, ba_window=0), event_only=True) == (6, 1)


def test_ba_window_stays_within_the_newest_visual_segment():
    from evpose.slam.local_map import visual_ba_window

    cfg = TrackingConfig(local_window=6, ba_window=10)
    assert visual_ba_window(_map_with_keyframes(12, segment_start=9), cfg, event_only=True)[0] == 3


def test_points_triangulated_at_a_predicted_pose_take_the_depth_level_of_the_older_points():
    from evpose.slam.local_map import triangulate_new_points

    # The predicted keyframe's baseline is 0.3 map units where the map's own scale would make it 0.6: its new points come
    # out at half the depth of the older points (same true depths, 4.5-5.5) until levelled to their median.
    m, K, t2p = _two_keyframes(0.3)
    for p in m.points.values():
        p.xyz = p.xyz * 2.0
    cfg = TrackingConfig(min_triangulation_deg=1.0, min_pair_parallax_deg=0.0, coast_depth_level=True)
    off = TrackingConfig(min_triangulation_deg=1.0, min_pair_parallax_deg=0.0)
    m2, _, t2p2 = _two_keyframes(0.3)
    for p in m2.points.values():
        p.xyz = p.xyz * 2.0
    triangulate_new_points(m2, K, m2.keyframes[1], t2p2, off, 1000, predicted=True)
    z_raw = np.median([p.xyz[2] for pid, p in m2.points.items() if pid >= 1000])
    triangulate_new_points(m, K, m.keyframes[1], t2p, cfg, 1000, predicted=True)
    z_new = np.median([p.xyz[2] for pid, p in m.points.items() if pid >= 1000])
    z_old = np.median([p.xyz[2] for pid, p in m.points.items() if pid < 1000])
    assert abs(z_raw / z_old - 0.5) < 0.05
    assert abs(z_new / z_old - 1.0) < 0.05
    # A keyframe placed by the images keeps its triangulation as it is.
    m3, _, t2p3 = _two_keyframes(0.3)
    for p in m3.points.values():
        p.xyz = p.xyz * 2.0
    triangulate_new_points(m3, K, m3.keyframes[1], t2p3, cfg, 1000, predicted=False)
    assert abs(np.median([p.xyz[2] for pid, p in m3.points.items() if pid >= 1000]) - z_raw) < 1e-9
