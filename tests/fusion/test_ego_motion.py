"""Ego-motion consistency filter on synthetic events from static ground lines and an independently moving box."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.fusion.ego_motion import EgoMotionConfig, EgoMotionFilter

W, H = 240, 180
K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])
R_DOWN = np.diag([1.0, -1.0, -1.0])


def _pose(t, v, w):
    T = np.eye(4)
    T[:3, :3] = R_DOWN @ Rotation.from_rotvec(w * t).as_matrix()
    T[:3, 3] = np.array([0.0, 0.0, 2.0]) + v * t
    return T


def _project(P, T):
    X = (P - T[:3, 3]) @ T[:3, :3]
    return K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]


def _scene():
    s = np.arange(-0.9, 0.9, 0.004)
    lines = [np.stack([np.full_like(s, c), s, np.zeros_like(s)], 1) for c in (-0.6, -0.2, 0.25, 0.7)]
    lines += [np.stack([s, np.full_like(s, c), np.zeros_like(s)], 1) for c in (-0.5, 0.1, 0.55)]
    static = np.concatenate(lines)
    e = np.arange(-0.15, 0.15, 0.004)
    box = np.concatenate([np.stack([e, np.full_like(e, y), np.full_like(e, 0.3)], 1) for y in (-0.15, 0.15)]
                         + [np.stack([np.full_like(e, x), e, np.full_like(e, 0.3)], 1) for x in (-0.15, 0.15)])
    return static, box


def _events(rng, static, box, v, w, box_v, span_us=30_000):
    xs, ys, ts, src = [], [], [], []
    for t_us in range(0, span_us, 250):
        T = _pose(t_us * 1e-6, v, w)
        for P, tag in ((static, 0), (box + box_v * t_us * 1e-6 + np.array([0.3, -0.2, 0.0]), 1)):
            pick = rng.random(P.shape[0]) < 0.08
            u, vv = _project(P[pick], T)
            ok = (u >= 0) & (u < W - 0.5) & (vv >= 0) & (vv < H - 0.5)
            xs.append(np.round(u[ok]))
            ys.append(np.round(vv[ok]))
            ts.append(t_us + rng.integers(0, 250, ok.sum()))
            src.append(np.full(ok.sum(), tag))
    x, y, t, s = (np.concatenate(a) for a in (xs, ys, ts, src))
    o = np.argsort(t, kind="stable")
    return x[o], y[o], t[o].astype(np.int64), s[o]


def test_moving_object_events_are_dropped_and_static_ones_kept():
    rng = np.random.default_rng(0)
    static, box = _scene()
    v, w = np.array([2.0, -1.0, -0.3]), np.array([0.3, -0.5, 0.8])
    x, y, t, src = _events(rng, static, box, v, w, box_v=np.array([-2.0, 2.5, 0.0]))
    f = EgoMotionFilter(EgoMotionConfig(enabled=True))
    keep = f.filter(x, y, t, _pose(0.015, v, w), w, v, K, W, H, points_world=static, t_ref_us=15_000)
    assert keep[src == 0].mean() > 0.9
    assert keep[src == 1].mean() < 0.3
    assert f.last_counts["events_removed"] == int((~keep).sum())


def test_fast_flight_keeps_static_events_only_with_ego_motion_compensation():
    # Judged with zero motion, static edges of a fast flight smear like moving objects: the IMU motion is what works.
    rng = np.random.default_rng(0)
    static, box = _scene()
    v, w = np.array([4.0, -2.0, -0.5]), np.array([0.5, -0.8, 1.5])
    x, y, t, src = _events(rng, static, box, v, w, box_v=np.array([-2.0, 2.5, 0.0]))
    T = _pose(0.015, v, w)
    compensated = EgoMotionFilter(EgoMotionConfig(enabled=True)).filter(x, y, t, T, w, v, K, W, H, points_world=static)
    blind = EgoMotionFilter(EgoMotionConfig(enabled=True)).filter(x, y, t, T, np.zeros(3), np.zeros(3), K, W, H, points_world=static)
    assert compensated[src == 0].mean() > 0.95 and compensated[src == 1].mean() < 0.3
    assert blind[src == 0].mean() < 0.7


def test_isolated_noise_events_are_dropped_and_sparse_windows_kept_whole():
    rng = np.random.default_rng(1)
    n = 2000
    x, y = rng.integers(0, W, n).astype(float), rng.integers(0, H, n).astype(float)
    t = np.sort(rng.integers(0, 20_000, n)).astype(np.int64)
    T = _pose(0.0, np.zeros(3), np.zeros(3))
    keep = EgoMotionFilter(EgoMotionConfig(enabled=True)).filter(x, y, t, T, np.zeros(3), np.zeros(3), K, W, H)
    assert keep.mean() < 0.5
    few = EgoMotionFilter(EgoMotionConfig(enabled=True, min_events=5000)).filter(x, y, t, T, np.zeros(3), np.zeros(3), K, W, H)
    assert few.all()


def test_a_short_batch_is_judged_against_earlier_context_events():
    # A 5 ms batch alone is too short to separate static from moving edges; 20 ms of context events make it work.
    rng = np.random.default_rng(0)
    static, box = _scene()
    v, w = np.array([2.0, -1.0, -0.3]), np.array([0.3, -0.5, 0.8])
    x, y, t, src = _events(rng, static, box, v, w, box_v=np.array([-2.0, 2.5, 0.0]), span_us=25_000)
    m = int(np.searchsorted(t, 20_000))
    T = _pose(0.025, v, w)
    f = EgoMotionFilter(EgoMotionConfig(enabled=True))
    with_context = f.filter(x, y, t, T, w, v, K, W, H, points_world=static, t_ref_us=25_000, n_context=m)
    assert with_context.shape == (len(t) - m,)
    assert f.last_counts["events"] == len(t) - m
    alone = EgoMotionFilter(EgoMotionConfig(enabled=True)).filter(x[m:], y[m:], t[m:], T, w, v, K, W, H, points_world=static, t_ref_us=25_000)
    s = src[m:]
    assert with_context[s == 0].mean() > 0.9 and with_context[s == 1].mean() < 0.3
    assert alone[s == 1].mean() > 0.8


def test_cached_depth_candidates_give_the_same_grid_as_the_whole_map():
    rng = np.random.default_rng(4)
    pts = np.c_[rng.uniform(-6, 6, 20000), rng.uniform(-6, 6, 20000), rng.uniform(0.0, 0.5, 20000)]
    cached = EgoMotionFilter(EgoMotionConfig(enabled=True))
    for k in range(40):
        T = _pose(k * 0.005, np.array([0.4, -0.2, -0.3]), np.array([0.2, 0.1, 0.3]))
        fresh = EgoMotionFilter(EgoMotionConfig(enabled=True)).depth_image(pts, T, K, W, H)
        assert np.array_equal(cached.depth_image(pts, T, K, W, H), fresh)
