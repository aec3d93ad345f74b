import numpy as np

from evpose.slam.atlas import MapPoint, SlamMap
from evpose.slam.track_fusion import fuse_tracks

K = np.array([[200.0, 0.0, 160.0], [0.0, 200.0, 120.0], [0.0, 0.0, 1.0]])
SHAPE = (240, 320)


def _map(xyz: list[tuple[float, float, float]]) -> SlamMap:
    m = SlamMap(0)
    for i, X in enumerate(xyz):
        m.points[i] = MapPoint(i, np.array(X, np.float64), {0: np.zeros(2), 1: np.zeros(2)}, track_id=100 + i)
    return m


def _pixel(X: tuple[float, float, float]) -> np.ndarray:
    return np.array([K[0, 0] * X[0] / X[2] + K[0, 2], K[1, 1] * X[1] / X[2] + K[1, 2]])


def test_fuse_tracks_attaches_a_new_track_to_the_old_point_under_it():
    pts = [(0.0, 0.0, 5.0), (1.0, 0.5, 5.0)]
    m = _map(pts)
    track_to_point = {}  # both points' tracks died
    ids = np.array([7, 8])
    uv = np.stack([_pixel(pts[0]) + [0.6, -0.4], _pixel(pts[1]) + [20.0, 0.0]]).astype(np.float32)
    n = fuse_tracks(m, K, np.eye(4), ids, uv, track_to_point, 1.5, SHAPE)
    assert n == 1
    assert track_to_point == {7: 0}
    assert m.points[0].track_id == 7
    assert m.points[1].track_id == 101  # track 8 lies 20 px from point 1: left alone


def test_fuse_tracks_leaves_points_that_are_still_tracked_and_tracks_that_have_a_point():
    pts = [(0.0, 0.0, 5.0), (1.0, 0.5, 5.0)]
    m = _map(pts)
    track_to_point = {100: 0, 9: 1}
    ids = np.array([100, 9, 7])
    uv = np.stack([_pixel(pts[0]), _pixel(pts[1]), _pixel(pts[0]) + [0.5, 0.0]]).astype(np.float32)
    # Track 7 sits on point 0, whose own track 100 is alive: no takeover. Track 9 keeps its point.
    assert fuse_tracks(m, K, np.eye(4), ids, uv, track_to_point, 1.5, SHAPE) == 0
    assert track_to_point == {100: 0, 9: 1}


def test_fuse_tracks_refuses_ambiguous_pairs():
    pts = [(0.0, 0.0, 5.0), (0.01, 0.0, 5.0)]  # two points 0.4 px apart in the image
    m = _map(pts)
    track_to_point = {}
    uv = (_pixel(pts[0]) + [0.2, 0.0]).astype(np.float32)[None]
    assert fuse_tracks(m, K, np.eye(4), np.array([7]), uv, track_to_point, 1.5, SHAPE) == 0
    # Two tracks near one point: neither takes it.
    m = _map([pts[0]])
    uv = np.stack([_pixel(pts[0]) + [0.5, 0.0], _pixel(pts[0]) + [-1.0, 0.0]]).astype(np.float32)
    assert fuse_tracks(m, K, np.eye(4), np.array([7, 8]), uv, track_to_point, 1.5, SHAPE) == 0
    assert track_to_point == {}


def test_fuse_tracks_ignores_points_behind_the_camera_or_outside_the_image_and_is_off_at_zero_radius():
    m = _map([(0.0, 0.0, -5.0), (10.0, 0.0, 5.0)])
    uv = np.array([[160.0, 120.0], [319.0, 120.0]], np.float32)
    assert fuse_tracks(m, K, np.eye(4), np.array([7, 8]), uv, {}, 1.5, SHAPE) == 0
    m = _map([(0.0, 0.0, 5.0)])
    assert fuse_tracks(m, K, np.eye(4), np.array([7]), _pixel((0.0, 0.0, 5.0)).astype(np.float32)[None], {}, 0.0, SHAPE) == 0




def test_event_only_tracking_hands_an_untracked_point_to_the_new_track_on_it_only_when_enabled():
    from evpose.slam import EventSlam, SlamConfig, SlamStatus
    from slam_synthetic import make_recording

    rec = make_recording(duration_s=1.0, speed=1.5, seed=9)
    half = len(rec.events) // 2 // 20000 * 20000
    taken = {}
    for radius in (0.0, 1.5):
        cfg = SlamConfig()
        cfg.search.enabled = False  # the projection search would re-find the points first
        cfg.search.fuse_radius_px = radius
        slam = EventSlam(cfg, rec.calibration)
        for a in range(0, half, 20000):
            slam.step(rec.events[a:a + 20000])
        assert slam.results[-1].status is SlamStatus.OK
        fe, m = slam.fe, slam.atlas.active
        # Five mapped tracks die and their features are detected again as new tracks, as after a sparse stretch.
        lost = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points][:5]
        for i in lost:
            del fe.track_to_point[int(fe.ids[i])]
            fe.ids[i] = fe.next_id
            fe.next_id += 1
        n0 = len(slam.results)
        for a in range(half, len(rec.events), 20000):
            slam.step(rec.events[a:a + 20000])
        ok = [r.reason for r in slam.results[n0:] if r.status is SlamStatus.OK and "inliers" in r.reason]
        assert ok
        taken[radius] = [int(s.split(" taken over")[0].split(", ")[-1]) for s in ok if "taken over" in s]
    assert taken[0.0] == []
    assert taken[1.5][0] >= 3
