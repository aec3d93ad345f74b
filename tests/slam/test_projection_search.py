"""Re-finding map points by projection: patch search on event images, uniqueness, and the map-level search."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.geometry import project
from evpose.slam.projection_search import (ProjectionSearchConfig, cut_patch, refind_points, search_by_projection, search_patch,
                                           store_patches)

W, H = 240, 180
K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])


def _corner_events(centres: np.ndarray, seed: int = 0, n: int = 120) -> tuple[np.ndarray, np.ndarray]:
    """An L-shaped corner of events (two 8 px edges, each orientation varied by the seed) at each centre."""
    rng = np.random.default_rng(seed)
    xs, ys = [], []
    for k, (cx, cy) in enumerate(centres):
        s = rng.uniform(0, 8, n)
        sx, sy = (1, 1) if k % 4 == 0 else (-1, 1) if k % 4 == 1 else (1, -1) if k % 4 == 2 else (-1, -1)
        xs += [cx + sx * s[: n // 2], np.full(n // 2, cx) + rng.normal(0, 0.2, n // 2)]
        ys += [np.full(n // 2, cy) + rng.normal(0, 0.2, n // 2), cy + sy * s[n // 2:]]
    return np.concatenate(xs), np.concatenate(ys)


def _image(centres: np.ndarray, seed: int) -> np.ndarray:
    x, y = _corner_events(centres, seed)
    return to_uint8(event_image(x, y, None, W, H, 1.0))


def test_patch_search_finds_a_shifted_corner_with_subpixel_accuracy():
    c0 = np.array([[60.0, 50.0], [160.0, 60.0], [100.0, 130.0]])
    shift = np.array([3.4, -2.3])
    a, b = _image(c0, seed=1), _image(c0 + shift, seed=2)  # other events, same corners moved
    cfg = ProjectionSearchConfig()
    for c in c0:
        patch = cut_patch(a, c, cfg.patch_px)
        found, score = search_patch(b, patch, c + shift + np.array([2.0, -1.5]), cfg.radius_px, cfg)
        assert found is not None and score >= cfg.min_ncc
        assert np.linalg.norm(found - (c + shift)) < 0.6


def test_patch_search_rejects_an_ambiguous_edge_and_a_missing_feature():
    cfg = ProjectionSearchConfig()
    rng = np.random.default_rng(3)
    # A long straight edge: a patch of it matches anywhere along the edge (aperture problem).
    x = rng.uniform(20, 220, 4000)
    y = np.full_like(x, 90.0) + rng.normal(0, 0.2, x.size)
    img = to_uint8(event_image(x, y, None, W, H, 1.0))
    patch = cut_patch(img, np.array([120.0, 90.0]), cfg.patch_px)
    assert search_patch(img, patch, np.array([121.0, 90.0]), cfg.radius_px, cfg)[0] is None
    # A corner whose surroundings in the new image are empty is not found.
    a = _image(np.array([[60.0, 50.0]]), seed=1)
    b = _image(np.array([[180.0, 140.0]]), seed=2)
    assert search_patch(b, cut_patch(a, np.array([60.0, 50.0]), cfg.patch_px), np.array([60.0, 50.0]), cfg.radius_px, cfg)[0] is None


def _scene():
    rng = np.random.default_rng(4)
    Xw = np.c_[rng.uniform(-1.5, 1.5, 30), rng.uniform(-1.0, 1.0, 30), rng.uniform(4.0, 6.0, 30)]
    T1 = np.eye(4)
    T2 = np.eye(4)
    T2[:3, 3] = [0.06, -0.03, 0.05]  # the camera moved: points shift by a few pixels
    uv1, _ = project(K, invert_pose(T1), Xw)
    uv2, _ = project(K, invert_pose(T2), Xw)
    inside = (uv1[:, 0] > 15) & (uv1[:, 0] < W - 15) & (uv1[:, 1] > 15) & (uv1[:, 1] < H - 15)
    inside &= (uv2[:, 0] > 15) & (uv2[:, 0] < W - 15) & (uv2[:, 1] > 15) & (uv2[:, 1] < H - 15)
    # Keep the corners apart so that no two patches overlap.
    keep = []
    for i in np.flatnonzero(inside):
        if all(np.linalg.norm(uv1[i] - uv1[j]) > 20 for j in keep):
            keep.append(i)
    return Xw[keep], T1, T2, uv1[keep], uv2[keep]


def test_map_points_are_re_found_by_projection_with_a_predicted_pose():
    Xw, T1, T2, uv1, uv2 = _scene()
    assert len(Xw) >= 6
    m = SlamMap(0)
    m.keyframes = [Keyframe(0, 0, T1, {})]
    for i, X in enumerate(Xw):
        m.points[i] = MapPoint(i, X.copy(), {0: uv1[i].copy()}, track_id=i)
    cfg = ProjectionSearchConfig()
    store_patches(m, 0, _image(uv1, seed=5), cfg.patch_px)
    assert all(p.patch is not None for p in m.points.values())
    cur = _image(uv2, seed=6)
    # The predicted pose is off by 1 cm: projections miss the corners by about a pixel.
    T_pred = T2.copy()
    T_pred[:3, 3] += [0.01, 0.0, 0.0]
    tracked = {0}  # point 0 is still tracked by KLT: not searched, and its pixel is occupied
    pids, uv = refind_points(m, cur, K, T_pred, tracked, uv2[[0]], window=6, radius=cfg.radius_px, cfg=cfg)
    assert 0 not in pids
    assert len(pids) >= 0.8 * (len(Xw) - 1)
    err = np.linalg.norm(uv - uv2[pids], axis=1)
    assert err.max() < 0.7
    # Determinism: the same search gives the same matches.
    pids2, uv2b = refind_points(m, cur, K, T_pred, tracked, uv2[[0]], window=6, radius=cfg.radius_px, cfg=cfg)
    assert pids2 == pids and np.array_equal(uv2b, uv)


def test_points_behind_the_camera_or_outside_the_image_are_not_searched():
    cfg = ProjectionSearchConfig()
    img = _image(np.array([[60.0, 50.0]]), seed=1)
    patch = cut_patch(img, np.array([60.0, 50.0]), cfg.patch_px)
    Xw = np.array([[0.0, 0.0, -5.0], [100.0, 0.0, 5.0]])
    idx, uv = search_by_projection(img, K, np.eye(4), Xw, [patch, patch], cfg.radius_px, cfg)
    assert len(idx) == 0 and uv.shape == (0, 2)
    assert cut_patch(img, np.array([2.0, 2.0]), cfg.patch_px) is None
