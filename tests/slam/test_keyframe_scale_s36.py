"""A keyframe's new points checked against the older points' depths (``TrackingConfig.new_point_depth_ratio``)."""

import numpy as np

from evpose.io.config_file import config_from_dict, config_to_dict
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import SlamConfig, TrackingConfig
from evpose.slam.keyframe_scale import NewPointAction, NewPointCheck, check_new_points, new_point_ratios

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _uv(X: np.ndarray) -> np.ndarray:
    """Pixel of camera-frame point ``X`` in a keyframe at the identity."""
    return np.array([K[0, 0] * X[0] / X[2] + K[0, 2], K[1, 1] * X[1] / X[2] + K[1, 2]])


def _map(old: list, new: list) -> tuple[SlamMap, dict[int, int]]:
    """Keyframe 1 at the identity sees older points (created at keyframe 0) ``old`` and new points ``new`` (created at
    keyframe 1); point ids 0.. for the old, 100.. for the new, track id = point id."""
    m = SlamMap(id=0)
    m.keyframes = [Keyframe(0, 0, np.eye(4)), Keyframe(1, 10000, np.eye(4))]
    t2p = {}
    for base, pts, created in ((0, old, 0), (100, new, 1)):
        for i, X in enumerate(pts):
            pid = base + i
            X = np.asarray(X, float)
            m.points[pid] = MapPoint(pid, X.copy(), {1: _uv(X)}, pid, created)
            m.keyframes[1].obs[pid] = _uv(X)
            t2p[pid] = pid
    return m, t2p


def _cfg(ratio: float, check: str = "median", action: str = "level") -> TrackingConfig:
    return TrackingConfig(new_point_depth_ratio=ratio, new_point_check=NewPointCheck(check), new_point_action=NewPointAction(action))


OLD = [(x, y, 2.0) for x in (-0.5, 0.0, 0.5) for y in (-0.3, 0.3)]


def test_median_ratio_is_new_over_old_depth():
    m, _ = _map(OLD, [(0.1, 0.1, 4.0), (-0.2, 0.0, 4.4), (0.3, -0.1, 3.6)])
    r = new_point_ratios(m, m.keyframes[1], NewPointCheck.MEDIAN)
    assert sorted(r) == [100, 101, 102]
    assert all(abs(v - 2.0) < 1e-9 for v in r.values())


def test_level_moves_new_points_along_their_ray_to_the_old_depth():
    new = [(0.1, 0.1, 4.0), (-0.2, 0.0, 4.4), (0.3, -0.1, 3.6)]
    m, t2p = _map(OLD, new)
    uv_before = {pid: _uv(m.points[pid].xyz) for pid in (100, 101, 102)}
    assert check_new_points(m, m.keyframes[1], t2p, _cfg(1.5)) == 3
    assert abs(np.median([m.points[p].xyz[2] for p in (100, 101, 102)]) - 2.0) < 1e-9
    for pid, uv in uv_before.items():
        assert np.allclose(_uv(m.points[pid].xyz), uv)  # unchanged in the keyframe's image
    assert all(np.allclose(m.points[i].xyz, OLD[i]) for i in range(len(OLD)))  # older points untouched


def test_within_the_limit_nothing_changes():
    new = [(0.1, 0.1, 2.5), (-0.2, 0.0, 2.6)]
    m, t2p = _map(OLD, new)
    assert check_new_points(m, m.keyframes[1], t2p, _cfg(1.5)) == 0
    assert np.allclose(m.points[100].xyz, new[0]) and np.allclose(m.points[101].xyz, new[1])


def test_off_by_default_and_at_ratio_one():
    assert TrackingConfig().new_point_depth_ratio == 0.0
    for cfg in (TrackingConfig(), _cfg(1.0)):
        m, t2p = _map(OLD, [(0.1, 0.1, 8.0)])
        assert check_new_points(m, m.keyframes[1], t2p, cfg) == 0
        assert m.points[100].xyz[2] == 8.0


def test_drop_removes_the_points_and_frees_their_tracks():
    m, t2p = _map(OLD, [(0.1, 0.1, 0.5), (-0.2, 0.0, 0.6)])
    assert check_new_points(m, m.keyframes[1], t2p, _cfg(1.5, action="drop")) == 2
    assert 100 not in m.points and 101 not in m.points and 100 not in t2p and 101 not in t2p
    assert len(m.points) == len(OLD) and all(t2p[i] == i for i in range(len(OLD)))


def test_local_check_judges_each_point_by_its_image_neighbours():
    # Older points: a near wall on the left (depth 1), a far one on the right (depth 4).
    old = [(-0.4, y, 1.0) for y in (-0.2, 0.0, 0.2)] + [(1.6, y, 4.0) for y in (-0.8, 0.0, 0.8)]
    # New points: one on each wall at its depth, one on the left at the far wall's depth.
    new = [(-0.38, 0.1, 1.0), (1.5, 0.4, 4.0), (-1.6, 0.4, 4.0)]
    m, t2p = _map(old, new)
    r = new_point_ratios(m, m.keyframes[1], NewPointCheck.LOCAL, neighbours=3)
    assert abs(r[100] - 1.0) < 1e-9 and abs(r[101] - 1.0) < 1e-9 and abs(r[102] - 4.0) < 1e-9
    m2, t2p2 = _map(old, new)
    assert check_new_points(m2, m2.keyframes[1], t2p2, _cfg(2.0, check="local", action="drop")) == 1
    assert sorted(p for p in m2.points if p >= 100) == [100, 101]
    # The median check sees the keyframe as consistent as a whole (new median 4 over old median 2.5: 1.6 < 2).
    m3, t2p3 = _map(old, new)
    assert check_new_points(m3, m3.keyframes[1], t2p3, _cfg(2.0, action="drop")) == 0


def test_too_few_older_points_skip_the_check():
    m, t2p = _map(OLD[:3], [(0.1, 0.1, 8.0)])
    assert new_point_ratios(m, m.keyframes[1], NewPointCheck.MEDIAN, min_old=5) == {}
    assert check_new_points(m, m.keyframes[1], t2p, _cfg(1.5)) == 0
    assert m.points[100].xyz[2] == 8.0


def test_config_round_trip_keeps_the_enums():
    cfg = SlamConfig()
    cfg.tracking.new_point_depth_ratio = 1.5
    cfg.tracking.new_point_check = NewPointCheck.LOCAL
    cfg.tracking.new_point_action = NewPointAction.DROP
    back = config_from_dict(SlamConfig, config_to_dict(cfg))
    assert back.tracking.new_point_depth_ratio == 1.5
    assert back.tracking.new_point_check is NewPointCheck.LOCAL and back.tracking.new_point_action is NewPointAction.DROP
