"""A contour map collapsed onto one position is refused when read, naming the map and the first point there: the
tracker's KD-tree queries are quadratic in the points stacked at one place (97 k identical points hung ``track``)."""

import numpy as np
import pytest

from evpose.core.contour_map import ContourMap
from evpose.errors import InputError
from evpose.io.map_ply import MAX_SHARED_POSITION, read_contour_map, write_contour_map


def _map_with_stack(tmp_path, stacked: int, n: int = 3000, name: str = "m.ply"):
    pts = np.random.default_rng(0).normal(size=(n, 3))
    pts[100:100 + stacked] = pts[100]
    path = tmp_path / name
    write_contour_map(path, ContourMap.from_points(pts))
    return path, pts[100]


def test_a_map_with_more_points_at_one_position_than_allowed_is_refused_naming_the_first(tmp_path):
    path, p = _map_with_stack(tmp_path, MAX_SHARED_POSITION + 1)
    with pytest.raises(InputError) as info:
        read_contour_map(path)
    assert str(info.value) == (f"{path}: point 100: {MAX_SHARED_POSITION + 1} of the 3000 points share the position {p.tolist()}"
                               " (a collapsed or damaged map; a contour map holds each position once)")


def test_a_few_repeated_points_are_read(tmp_path):
    path, _ = _map_with_stack(tmp_path, MAX_SHARED_POSITION)
    assert len(read_contour_map(path)) == 3000


def test_a_plain_cloud_given_as_the_map_is_checked_too(tmp_path):
    import open3d as o3d

    pts = np.zeros((2000, 3))
    pts[:5] = np.eye(5, 3)
    path = tmp_path / "scan.pcd"
    o3d.io.write_point_cloud(str(path), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts)))
    with pytest.raises(InputError, match=r"scan.pcd: point 3: 1997 of the 2000 points share the position \[0.0, 0.0, 0.0\]"):
        read_contour_map(path)


def test_track_with_a_collapsed_map_exits_2_at_once_with_one_line(tmp_path, capsys):
    from evpose.cli.main import run

    path, _ = _map_with_stack(tmp_path, 2900)
    rec = tmp_path / "rec.h5"
    rec.write_bytes(b"not read: the map is refused first")
    assert run(["track", str(rec), "--map", str(path), "--out", str(tmp_path / "est.txt"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path}: point 100: 2900 of the 3000 points share the position" in err
    assert not (tmp_path / "est.txt").exists()
