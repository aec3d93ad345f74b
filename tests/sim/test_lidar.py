"""The raw LiDAR-like cloud and the true edges of a scene."""

import numpy as np

from evpose.sim.lidar import LidarConfig, sample_cloud, write_cloud_ply, write_edges_npz
from evpose.sim.scene_library import _BUILDINGS, _CLUTTER, _CRATES, FAN_XY, MARKER_ALBEDO, PAD_ALBEDO, PAD_HEIGHT_M, PAD_SIZE_M, SceneOptions, indoor_scene, landing_scene


def _distance_to_mesh(points, mesh):
    import open3d as o3d

    rc = o3d.t.geometry.RaycastingScene()
    rc.add_triangles(o3d.core.Tensor(mesh.vertices.astype(np.float32)), o3d.core.Tensor(mesh.triangles.astype(np.uint32)))
    return rc.compute_distance(o3d.core.Tensor(points.astype(np.float32))).numpy()


def test_cloud_lies_on_static_surfaces_within_range_noise():
    scene = landing_scene(SceneOptions(dynamic=True))
    pts, inten = sample_cloud(scene, LidarConfig(density_per_m2=5.0, range_noise_m=0.004), np.random.default_rng(0))
    d = _distance_to_mesh(pts, scene.static)
    assert 0.0025 < np.mean(d) < 0.004  # |N(0, 4 mm)| has mean 4 mm * sqrt(2 / pi) = 3.2 mm
    assert np.percentile(d, 99) < 0.02
    assert inten.min() >= 0.0 and inten.max() <= 1.0


def test_cloud_excludes_moving_objects_and_hidden_ground():
    scene = landing_scene(SceneOptions(dynamic=True))
    pts, _ = sample_cloud(scene, LidarConfig(density_per_m2=20.0, range_noise_m=0.0), np.random.default_rng(0))
    # The fan's blades turn 1.2 m above the ground (over the pad's 0.15 m top): none of it may be in the map.
    near_fan = np.linalg.norm(pts[:, :2] - np.array(FAN_XY), axis=1) < 0.75
    assert near_fan.any() and not np.any(near_fan & (pts[:, 2] > PAD_HEIGHT_M + 0.05))
    # Under the 4 x 6 m building at (8, 3), the ground is hidden.
    under = (np.abs(pts[:, 0] - 8.0) < 1.9) & (np.abs(pts[:, 1] - 3.0) < 2.9) & (pts[:, 2] < 0.01)
    assert not under.any()


def test_cloud_intensity_shows_the_pad_marker():
    scene = landing_scene()
    pts, inten = sample_cloud(scene, LidarConfig(density_per_m2=30.0, range_noise_m=0.0), np.random.default_rng(1))
    on_pad = (np.abs(pts[:, 2] - PAD_HEIGHT_M) < 1e-6) & (np.abs(pts[:, :2]) < PAD_SIZE_M / 2 - 0.05).all(axis=1)
    vals = np.unique(np.round(inten[on_pad], 3))
    assert set(vals.tolist()) == {PAD_ALBEDO, MARKER_ALBEDO}  # dark pad, bright 'H'


def test_indoor_cloud_keeps_floor_outside_furniture_and_ceiling():
    scene = indoor_scene()
    pts, _ = sample_cloud(scene, LidarConfig(density_per_m2=10.0, range_noise_m=0.0), np.random.default_rng(0))
    floor = pts[:, 2] < 1e-6
    ceiling = pts[:, 2] > 3.0 - 1e-6
    assert floor.sum() > 200 and ceiling.sum() > 200
    under_table = floor & (np.abs(pts[:, 0] - 2.6) < 0.75) & (np.abs(pts[:, 1] - 0.5) < 0.4)
    assert not under_table.any()


def test_edges_and_cloud_files_round_trip(tmp_path):
    from evpose.io.map_ply import read_point_cloud

    scene = landing_scene()
    pts, inten = sample_cloud(scene, LidarConfig(density_per_m2=2.0), np.random.default_rng(0))
    write_cloud_ply(tmp_path / "c.ply", pts, inten)
    write_edges_npz(tmp_path / "e.npz", scene.edges, scene.albedo_edges)
    back, extra = read_point_cloud(tmp_path / "c.ply")
    np.testing.assert_allclose(back, pts)
    np.testing.assert_allclose(extra["colors"][:, 0], inten, atol=1 / 255)
    with np.load(tmp_path / "e.npz") as z:
        assert z["segments"].shape == scene.edges.shape and z["segments"].dtype == np.float64
        # The pad and every building, crate and piece of street furniture contribute 12 box edges.
        assert z["segments"].shape[0] == 12 * (1 + len(_BUILDINGS) + len(_CRATES) + len(_CLUTTER))


def test_cloud_ply_has_open3d_layout_and_reads_back_with_open3d(tmp_path):
    import open3d as o3d

    rng = np.random.default_rng(3)
    pts, inten = rng.normal(size=(500, 3)), np.concatenate([rng.uniform(-0.2, 1.2, 490), np.linspace(0.0, 1.0, 10)])
    write_cloud_ply(tmp_path / "ours.ply", pts, inten)
    ref = o3d.geometry.PointCloud()
    ref.points = o3d.utility.Vector3dVector(pts)
    ref.colors = o3d.utility.Vector3dVector(np.repeat(np.clip(inten, 0.0, 1.0)[:, None], 3, axis=1))
    assert o3d.io.write_point_cloud(str(tmp_path / "o3d.ply"), ref, write_ascii=False, compressed=False)
    assert (tmp_path / "ours.ply").read_bytes() == (tmp_path / "o3d.ply").read_bytes()
    back = o3d.io.read_point_cloud(str(tmp_path / "ours.ply"))
    assert np.array_equal(np.asarray(back.points), pts)
