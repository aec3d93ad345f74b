"""Revisiting old map points at a new keyframe with wide templates warped through the relative pose."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.geometry import project
from evpose.slam.projection_search import ProjectionSearchConfig
from evpose.slam.revisit_search import revisit_points, store_contexts

W, H = 240, 180
K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])
DEPTH = 5.0


def _plane_segments(seed: int = 0, n: int = 60) -> np.ndarray:
    """Random short line segments on the plane z = DEPTH (world), (n, 2 ends, 3)."""
    rng = np.random.default_rng(seed)
    a = np.c_[rng.uniform(-3.5, 3.5, n), rng.uniform(-2.5, 2.5, n), np.full(n, DEPTH)]
    ang = rng.uniform(0, np.pi, n)
    b = a + np.c_[np.cos(ang), np.sin(ang), np.zeros(n)] * rng.uniform(0.2, 0.5, n)[:, None]
    return np.stack([a, b], axis=1)


def _view(T_wc: np.ndarray, segs: np.ndarray, seed: int) -> np.ndarray:
    """An event image of the segments (events sampled along each) seen from ``T_wc``."""
    rng = np.random.default_rng(seed)
    s = rng.uniform(0, 1, (len(segs), 80))
    P = segs[:, :1] + s[..., None] * (segs[:, 1:] - segs[:, :1])
    uv, _ = project(K, invert_pose(T_wc), P.reshape(-1, 3))
    uv = uv + rng.normal(0, 0.2, uv.shape)
    return to_uint8(event_image(uv[:, 0], uv[:, 1], None, W, H, 1.0))


def _pose(yaw_deg: float, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("z", yaw_deg, degrees=True).as_matrix()
    T[:3, 3] = t
    return T


def _map(segs: np.ndarray, n_window: int) -> tuple[SlamMap, np.ndarray, int]:
    """A map whose keyframe 0 observed the segments' end points; ``n_window`` later keyframes see nothing of them."""
    m = SlamMap(0)
    T0 = _pose(0.0, [0, 0, 0])
    m.keyframes = [Keyframe(i, i, T0.copy()) for i in range(n_window + 1)]
    X = segs[:, 0]
    uv, _ = project(K, invert_pose(T0), X)
    inside = (uv[:, 0] > 30) & (uv[:, 0] < W - 30) & (uv[:, 1] > 30) & (uv[:, 1] < H - 30)
    for i in np.flatnonzero(inside):
        m.points[int(i)] = MapPoint(int(i), X[i].copy(), {0: uv[i].copy()})
    return m, T0, int(inside.sum())


def test_revisit_finds_old_points_in_a_turned_view_at_their_true_pixels():
    segs = _plane_segments()
    m, T0, n = _map(segs, n_window=3)
    cfg = ProjectionSearchConfig(revisit_patch_px=31)
    store_contexts(m, 0, _view(T0, segs, seed=1), cfg)
    T1 = _pose(15.0, [0.3, -0.2, 0.4])  # a 15 deg turn about the optical axis and a step towards the plane
    kf = Keyframe(4, 4, T1)
    m.keyframes.append(kf)
    true = {pid: project(K, invert_pose(T1), p.xyz[None])[0][0] for pid, p in m.points.items()}
    for p in m.points.values():  # the map's positions are off by a few pixels, as the SLAM's old points are
        p.xyz = p.xyz + np.array([0.06, -0.04, 0.0])
    found = revisit_points(m, kf, _view(T1, segs, seed=2), K, window=3, cfg=cfg)
    hits = {pid: p.obs[4] for pid, p in m.points.items() if 4 in p.obs}
    assert found == len(hits) and found >= n // 3
    err = np.array([np.linalg.norm(uv - true[pid]) for pid, uv in hits.items()])
    assert np.mean(err < 1.5) >= 0.9


def test_revisit_is_off_by_default_and_skips_points_of_the_local_window():
    segs = _plane_segments()
    m, T0, _ = _map(segs, n_window=3)
    img = _view(T0, segs, seed=1)
    store_contexts(m, 0, img, ProjectionSearchConfig())
    assert all(p.context is None for p in m.points.values())
    cfg = ProjectionSearchConfig(revisit_patch_px=31)
    store_contexts(m, 0, img, cfg)
    kf = Keyframe(4, 4, T0.copy())
    m.keyframes.append(kf)
    assert revisit_points(m, kf, img, K, window=3, cfg=ProjectionSearchConfig()) == 0
    # With a local window reaching keyframe 0 the points are the ordinary search's, not the revisit's.
    assert revisit_points(m, kf, img, K, window=5, cfg=cfg) == 0
