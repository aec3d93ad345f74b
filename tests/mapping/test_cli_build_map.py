"""``evpose build-map`` end to end (evpose/cli/build_map.py) and cloud reading (evpose/mapping/cloud_input.py)."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.cli.main import run
from evpose.errors import InputError
from evpose.io.map_ply import read_contour_map
from evpose.mapping.cloud_input import load_cloud
from evpose.mapping.synthetic import Box, boxes_on_ground


@pytest.fixture(scope="module")
def small_scan():
    return boxes_on_ground((Box((0.0, 0.0), (0.8, 0.8, 0.4), albedo_top=0.9),), half_extent=1.2, seed=8)


def _write_ply_with_colours(path, scan):
    import open3d as o3d

    pcd = o3d.geometry.PointCloud()
    pcd.points = o3d.utility.Vector3dVector(scan.points)
    pcd.colors = o3d.utility.Vector3dVector(np.repeat(scan.intensity[:, None], 3, axis=1))
    o3d.io.write_point_cloud(str(path), pcd)


def _write_pcd_with_intensity(path, scan):
    import open3d as o3d

    pc = o3d.t.geometry.PointCloud(o3d.core.Tensor(scan.points))
    pc.point["intensity"] = o3d.core.Tensor(scan.intensity[:, None].astype(np.float32) * 255)
    o3d.t.io.write_point_cloud(str(path), pc)


def test_build_map_writes_a_contour_map_the_tracker_can_read(tmp_path, small_scan, capsys):
    cloud = tmp_path / "scan_cloud.ply"
    _write_ply_with_colours(cloud, small_scan)
    out = tmp_path / "scan_map.ply"
    assert run(["build-map", str(cloud), "--out", str(out), "--quiet"]) == 0
    cmap = read_contour_map(out)
    assert len(cmap) > 100 and cmap.has_edge_normals
    assert np.any(cmap.brightness_sign != 0)
    assert set(np.unique(cmap.region_id)) <= set(range(100))


def test_pcd_intensity_field_is_read_as_brightness(tmp_path, small_scan):
    cloud = tmp_path / "scan.pcd"
    _write_pcd_with_intensity(cloud, small_scan)
    raw = load_cloud(cloud)
    assert raw.intensity is not None and raw.intensity.shape == (small_scan.points.shape[0],)
    assert np.allclose(raw.points, small_scan.points, atol=1e-5)


@pytest.mark.parametrize(
    "content, name, message",
    [
        (b"hello, not a cloud\n", "junk.pcd", "no points could be read"),
        (b"not a ply\n", "junk.ply", "not a PLY file"),
        (b"x y z\n", "cloud.txt", "not a point-cloud file"),
    ],
)
def test_bad_files_fail_with_one_line_and_exit_code_2(tmp_path, capsys, content, name, message):
    bad = tmp_path / name
    bad.write_bytes(content)
    assert run(["build-map", str(bad), "--out", str(tmp_path / "m.ply"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and name in err[0]
    assert not (tmp_path / "m.ply").exists()


def test_coplanar_cloud_without_contour_exits_2(tmp_path, capsys):
    flat = boxes_on_ground((), half_extent=1.0, seed=9)
    cloud = tmp_path / "flat.ply"
    _write_ply_with_colours(cloud, flat)
    assert run(["build-map", str(cloud), "--out", str(tmp_path / "m.ply"), "--quiet"]) == 2
    assert "no object contour" in capsys.readouterr().err


def test_nan_point_is_reported_with_its_index(tmp_path, small_scan, capsys):
    bad = tmp_path / "nan.ply"
    pts = small_scan.points[:50].copy()
    pts[7, 0] = np.nan
    header = f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    bad.write_text(header + "\n".join(f"{x} {y} {z}" for x, y, z in pts) + "\n")
    with pytest.raises(InputError, match="point 7"):
        load_cloud(bad)
    assert run(["build-map", str(bad), "--out", str(tmp_path / "m.ply"), "--quiet"]) == 2
    assert "point 7" in capsys.readouterr().err


def test_output_onto_the_input_is_refused(tmp_path, small_scan, capsys):
    cloud = tmp_path / "scan.ply"
    _write_ply_with_colours(cloud, small_scan)
    before = cloud.read_bytes()
    assert run(["build-map", str(cloud), "--out", str(cloud), "--quiet"]) == 2
    assert cloud.read_bytes() == before


def test_build_map_traces_a_painted_panel_unless_told_not_to(tmp_path):
    from evpose.mapping.synthetic import painted_plane

    scan = painted_plane(size=2.0, panel=(0.6, 0.5, 0.8, 0.9), density=900.0, seed=5)
    cloud = tmp_path / "panel_cloud.ply"
    _write_ply_with_colours(cloud, scan)
    out = tmp_path / "panel_map.ply"
    assert run(["build-map", str(cloud), "--out", str(out), "--quiet"]) == 0
    cmap = read_contour_map(out)
    assert len(cmap) > 200 and np.all(cmap.brightness_sign == 1)
    # Without brightness edges a lone plane has no contour: a one-line error, exit code 2.
    assert run(["build-map", str(cloud), "--out", str(tmp_path / "none.ply"), "--quiet", "--no-albedo-edges"]) == 2


def test_build_map_defaults_are_the_library_defaults():
    # The CLI spells its defaults out for tyro; they must stay those of MapBuildConfig.
    import inspect

    from evpose.cli.build_map import main
    from evpose.mapping import MapBuildConfig

    params = inspect.signature(main).parameters
    cfg = MapBuildConfig()
    pairs = {"k": cfg.k_neighbours, "angle_deg": cfg.angle_threshold_deg, "plane_angle_deg": cfg.plane_angle_deg,
             "curvature": cfg.curvature_limit, "min_region": cfg.min_region_points,
             "plane_distance": cfg.plane_distance_m, "no_robust_normals": not cfg.robust_normals,
             "no_snap": not cfg.snap, "no_albedo_edges": not cfg.albedo_edges}
    for name, value in pairs.items():
        assert params[name].default == value, name


def test_build_map_reads_every_setting_from_a_config_file_and_flags_override_it(tmp_path, small_scan, capsys):
    cloud = tmp_path / "scan_cloud.ply"
    _write_ply_with_colours(cloud, small_scan)
    (tmp_path / "coarse.yaml").write_text("contour_spacing_m: 0.04\nleftover_regions: false\n")
    base, coarse, flagged = tmp_path / "a.ply", tmp_path / "b.ply", tmp_path / "c.ply"
    assert run(["build-map", str(cloud), "--out", str(base), "--quiet"]) == 0
    assert run(["build-map", str(cloud), "--out", str(coarse), "--config", str(tmp_path / "coarse.yaml"), "--quiet"]) == 0
    assert run(["build-map", str(cloud), "--out", str(flagged), "--config", str(tmp_path / "coarse.yaml"), "--spacing", "0.02",
                "--quiet"]) == 0
    n = [len(read_contour_map(p)) for p in (base, coarse, flagged)]
    assert n[1] < n[2] < n[0]  # 4 cm spacing from the file, the flag's 2 cm over it, the default 1 cm
    (tmp_path / "bad.yaml").write_text("contour_spacing: 0.04\n")
    assert run(["build-map", str(cloud), "--out", str(tmp_path / "d.ply"), "--config", str(tmp_path / "bad.yaml")]) == 2
    assert "bad.yaml: contour_spacing: unknown setting" in capsys.readouterr().err
