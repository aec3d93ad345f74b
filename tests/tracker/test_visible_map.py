"""Visible map: FoV with margin, depth range and occlusion by a coarse z-buffer."""

import numpy as np

from evpose.tracker.visible_map import VisibleMapConfig, visible_points

K = np.array([[100.0, 0.0, 49.5], [0.0, 100.0, 39.5], [0.0, 0.0, 1.0]])
W, H = 100, 80


def test_points_in_front_and_inside_the_image_are_visible():
    pts = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, -2.0], [5.0, 0.0, 2.0], [1.2, 0.0, 2.0]])
    idx = visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(fov_margin_px=0.0, occlusion=False))
    assert idx.tolist() == [0]  # behind, far outside, and 10 px outside with no margin


def test_margin_keeps_points_just_outside_the_image():
    pts = np.array([[0.0, 0.0, 2.0], [1.1, 0.0, 2.0]])  # second projects at u = 104.5
    assert visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(fov_margin_px=10.0, occlusion=False)).tolist() == [0, 1]
    assert visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(fov_margin_px=2.0, occlusion=False)).tolist() == [0]


def test_culling_uses_the_camera_pose():
    pts = np.array([[0.0, 0.0, 2.0]])
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 3.0]  # camera moved past the point
    assert visible_points(pts, T, K, W, H, VisibleMapConfig()).size == 0


def test_occlusion_drops_points_behind_a_nearer_surface_in_the_same_cell():
    near = np.array([[0.0, 0.0, 1.0], [0.002, 0.0, 1.0]])
    far = np.array([[0.0, 0.0, 3.0], [0.006, 0.0, 3.0]])
    pts = np.concatenate([near, far])
    on = visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(occlusion=True, occlusion_cell_px=8))
    off = visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(occlusion=False))
    assert on.tolist() == [0, 1] and off.tolist() == [0, 1, 2, 3]


def test_points_of_one_edge_at_a_similar_depth_survive_together():
    pts = np.array([[0.0, 0.0, 2.0], [0.001, 0.0, 2.1]])
    assert visible_points(pts, np.eye(4), K, W, H, VisibleMapConfig(occlusion_tolerance=0.1)).tolist() == [0, 1]


def test_cached_culling_equals_the_exact_cull_along_a_path():
    from scipy.spatial.transform import Rotation

    from evpose.tracker.visible_map import VisibleMap

    rng = np.random.default_rng(0)
    pts = np.concatenate([rng.uniform([-3, -3, 0], [3, 3, 0.5], (4000, 3)), rng.uniform([-0.3, -0.3, 1.0], [0.3, 0.3, 1.5], (500, 3))])
    vm = VisibleMap(pts, K, W, H)
    cfg = VisibleMapConfig()
    base = Rotation.from_matrix(np.diag([1.0, -1.0, -1.0]))
    for k in range(60):
        T = np.eye(4)
        T[:3, :3] = (Rotation.from_rotvec([0.01 * k, -0.005 * k, 0.02 * k]) * base).as_matrix()
        T[:3, 3] = [0.02 * k, -0.01 * k, 2.0 - 0.01 * k]
        assert np.array_equal(vm.visible(T, cfg), visible_points(pts, T, K, W, H, cfg))


def test_default_culls_the_hidden_bottom_edge_of_a_low_box_seen_from_above():
    # Looking straight down from 4 m at a 0.5 m box: its top rim (3.5 m away) hides the
    # ground contact line right below it (4 m away), 14 % deeper.
    top = np.array([[0.0, 0.0, 3.5], [0.005, 0.0, 3.5]])
    bottom = np.array([[0.0, 0.0, 4.0], [0.006, 0.0, 4.0]])
    idx = visible_points(np.concatenate([top, bottom]), np.eye(4), K, W, H, VisibleMapConfig())
    assert idx.tolist() == [0, 1]


def test_projected_bounds_are_those_of_the_pinhole_projection():
    from evpose.tracker.visible_map import projected_bounds

    rng = np.random.default_rng(3)
    pts = rng.uniform([-2.0, -1.5, 1.0], [2.0, 1.5, 6.0], size=(500, 3))
    T = np.eye(4)
    T[:3, :3] = np.array([[np.cos(0.2), 0.0, np.sin(0.2)], [0.0, 1.0, 0.0], [-np.sin(0.2), 0.0, np.cos(0.2)]])
    T[:3, 3] = [0.3, -0.1, -0.5]
    Xc = (pts - T[:3, 3]) @ T[:3, :3]
    u = K[0, 0] * Xc[:, 0] / Xc[:, 2] + K[0, 2]
    v = K[1, 1] * Xc[:, 1] / Xc[:, 2] + K[1, 2]
    assert np.allclose(projected_bounds(pts, T, K), (u.min(), u.max(), v.min(), v.max()), rtol=0, atol=1e-9)


def test_culling_matches_a_direct_reference_with_occlusion_on_random_points():
    # Reference: project, keep the FoV (with margin) and depth range, then drop points deeper than
    # (1 + tol) x the nearest point of their 8 px cell.
    rng = np.random.default_rng(5)
    pts = rng.uniform([-3.0, -2.0, -1.0], [3.0, 2.0, 8.0], size=(4000, 3))
    cfg = VisibleMapConfig(fov_margin_px=15.0, occlusion=True, occlusion_cell_px=8, occlusion_tolerance=0.05)
    Z = pts[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = K[0, 0] * pts[:, 0] / Z + K[0, 2]
        v = K[1, 1] * pts[:, 1] / Z + K[1, 2]
    m = cfg.fov_margin_px
    ok = (Z > cfg.min_depth_m) & (Z < cfg.max_depth_m) & (u >= -m) & (u <= W - 1 + m) & (v >= -m) & (v <= H - 1 + m)
    idx = np.flatnonzero(ok)
    gw = int((W + 2 * m) // 8) + 1
    cell = ((v[idx] + m) // 8).astype(int) * gw + ((u[idx] + m) // 8).astype(int)
    nearest = {}
    for c, z in zip(cell, Z[idx]):
        nearest[c] = min(nearest.get(c, np.inf), z)
    expected = [i for i, c in zip(idx, cell) if Z[i] <= nearest[c] * 1.05]
    assert visible_points(pts, np.eye(4), K, W, H, cfg).tolist() == expected


def test_block_wise_superset_cull_equals_the_per_point_cull_from_any_pose():
    import dataclasses

    from evpose.tracker.visible_map import VisibleMap

    # Contour-like map: random walks, so consecutive points are neighbours (small blocks), some far away.
    rng = np.random.default_rng(11)
    walks = [rng.uniform(-20, 20, 3) + np.cumsum(rng.normal(0, 0.02, (300, 3)), axis=0) for _ in range(40)]
    pts = np.concatenate(walks)
    vm = VisibleMap(pts, K, W, H)
    wide = dataclasses.replace(VisibleMapConfig(), fov_margin_px=60.0, occlusion=False)
    for _ in range(30):
        T = np.eye(4)
        a = rng.normal(0, 1.0, 3)
        c, s = np.cos(np.linalg.norm(a)), np.sin(np.linalg.norm(a))
        k = a / np.linalg.norm(a)
        Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        T[:3, :3] = np.eye(3) + s * Kx + (1 - c) * Kx @ Kx
        T[:3, 3] = rng.uniform(-15, 15, 3)
        assert vm._superset(T, wide).tolist() == visible_points(pts, T, K, W, H, wide).tolist()
