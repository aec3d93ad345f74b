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
