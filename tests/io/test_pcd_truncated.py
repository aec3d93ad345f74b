"""A PCD whose header promises more points than its data holds is refused as truncated, naming the file: open3d
filled the missing points with zeros or left them uninitialised, and a cut scan was read as garbage."""

import numpy as np
import pytest

from evpose.errors import InputError
from evpose.io.map_ply import read_contour_map, read_point_cloud


def _pcd(tmp_path, binary: bool, n: int = 500):
    import open3d as o3d

    pts = np.random.default_rng(0).uniform(-1, 1, size=(n, 3))
    path = tmp_path / ("b.pcd" if binary else "a.pcd")
    o3d.io.write_point_cloud(str(path), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts)), write_ascii=not binary)
    return path


@pytest.mark.parametrize("binary", [False, True])
def test_a_cut_pcd_is_truncated_not_zeros_or_garbage(tmp_path, binary):
    path = _pcd(tmp_path, binary)
    data = path.read_bytes()
    header = data.index(b"DATA")
    path.write_bytes(data[: header + (len(data) - header) // 2])
    for read in (read_point_cloud, read_contour_map):
        with pytest.raises(InputError) as info:
            read(path)
        msg = str(info.value)
        assert msg.startswith(f"{path}: file is truncated: header promises 500 points, the data holds ") and "\n" not in msg


def test_a_header_promising_more_points_than_the_lines_is_refused(tmp_path):
    # `evpose info` described 916903 points, 900000 of them at the origin, for a scan of 16903.
    path = _pcd(tmp_path, binary=False)
    path.write_text(path.read_text().replace("POINTS 500", "POINTS 9500").replace("WIDTH 500", "WIDTH 9500"))
    with pytest.raises(InputError, match=r"a.pcd: file is truncated: header promises 9500 points, the data holds 500$"):
        read_point_cloud(path)


@pytest.mark.parametrize("binary", [False, True])
def test_a_whole_pcd_reads(tmp_path, binary):
    assert read_point_cloud(_pcd(tmp_path, binary))[0].shape == (500, 3)


def test_build_map_on_a_cut_pcd_is_one_line(tmp_path, capsys):
    from evpose.cli.main import run

    path = _pcd(tmp_path, binary=True)
    path.write_bytes(path.read_bytes()[:-600])
    assert run(["build-map", str(path), "--out", str(tmp_path / "m.ply"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path}: file is truncated: header promises 500 points, the data holds 450" in err  # 12 bytes a point
