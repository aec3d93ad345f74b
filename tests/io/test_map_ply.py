"""read_contour_map refuses per-point attributes the tracker cannot use, naming the point."""

import numpy as np
import pytest

from evpose.core.contour_map import ContourMap
from evpose.errors import InputError
from evpose.io.map_ply import read_contour_map, write_contour_map


def _map(n=5, **overrides) -> ContourMap:
    attrs = {
        "edge_normal": np.tile([1.0, 0.0, 0.0], (n, 1)),
        "plane_normal": np.tile([0.0, 0.0, 1.0], (n, 1)),
        "curvature": np.full(n, 0.01),
        "brightness_sign": np.ones(n),
    }
    attrs.update(overrides)
    return ContourMap.from_points(np.arange(3 * n, dtype=float).reshape(n, 3) * 0.1, **attrs)


def _round_trip(tmp_path, cmap):
    path = tmp_path / "m.ply"
    write_contour_map(path, cmap)
    return read_contour_map(path)


def test_valid_map_with_unknown_zero_normals_reads_back(tmp_path):
    en = np.tile([1.0, 0.0, 0.0], (5, 1))
    en[2] = 0.0  # unknown edge normal
    got = _round_trip(tmp_path, _map(edge_normal=en, brightness_sign=[-1, 0, 1, 0, 1]))
    assert np.array_equal(got.edge_normal, en.astype(np.float32)) and got.brightness_sign.tolist() == [-1, 0, 1, 0, 1]


@pytest.mark.parametrize("key, label", [("edge_normal", "edge normal"), ("plane_normal", "plane normal")])
def test_nan_normal_names_the_point(tmp_path, key, label):
    n = np.tile([0.0, 1.0, 0.0], (5, 1))
    n[3, 1] = np.nan
    with pytest.raises(InputError, match=rf"m.ply: point 3: NaN or infinite {label}"):
        _round_trip(tmp_path, _map(**{key: n}))


def test_normal_that_is_not_a_unit_vector_names_the_point(tmp_path):
    n = np.tile([0.0, 1.0, 0.0], (5, 1))
    n[1] = [0.0, 0.5, 0.0]
    with pytest.raises(InputError, match=r"point 1: edge normal has length 0.5"):
        _round_trip(tmp_path, _map(edge_normal=n))


def test_brightness_sign_outside_minus_one_to_one_names_the_point(tmp_path):
    with pytest.raises(InputError, match=r"point 4: brightness_sign is 7 \(expected -1, 0 or \+1\)"):
        _round_trip(tmp_path, _map(brightness_sign=[1, 0, -1, 1, 7]))


def test_nan_curvature_names_the_point(tmp_path):
    with pytest.raises(InputError, match="point 0: NaN or infinite curvature"):
        _round_trip(tmp_path, _map(curvature=[np.nan, 0, 0, 0, 0]))


def test_coordinate_beyond_the_earth_is_refused_not_a_kd_tree_overflow(tmp_path):
    cmap = _map()
    pts = cmap.points.copy()
    pts[2, 0] = 1e300
    with pytest.raises(InputError, match=r"point 2: coordinate .* is beyond 1e\+07 m"):
        _round_trip(tmp_path, ContourMap(pts, cmap.edge_normal, cmap.plane_normal, cmap.region_id, cmap.curvature, cmap.brightness_sign))


def test_a_big_endian_contour_map_keeps_its_attributes(tmp_path):
    # It went to open3d, which kept the points and dropped the edge normals, regions and signs without a word.
    import numpy as np

    from evpose.core.contour_map import ContourMap
    from evpose.io.map_ply import _NAMES, _SCHEMA, read_contour_map

    rng = np.random.default_rng(0)
    n = 50
    en = rng.normal(size=(n, 3))
    cm = ContourMap.from_points(rng.normal(size=(n, 3)), edge_normal=en / np.linalg.norm(en, axis=1, keepdims=True),
                                region_id=np.arange(n), brightness_sign=rng.integers(-1, 2, n))
    rec = np.empty(n, dtype=[(name, ">" + t) for name, t in _SCHEMA])
    rec["x"], rec["y"], rec["z"] = cm.points.T
    rec["enx"], rec["eny"], rec["enz"] = cm.edge_normal.T
    rec["nx"], rec["ny"], rec["nz"] = cm.plane_normal.T
    rec["region"], rec["curvature"], rec["brightness_sign"] = cm.region_id, cm.curvature, cm.brightness_sign
    header = ["ply", "format binary_big_endian 1.0", f"element vertex {n}"] + [f"property {_NAMES[t]} {k}" for k, t in _SCHEMA] + ["end_header"]
    (tmp_path / "be.ply").write_bytes(("\n".join(header) + "\n").encode() + rec.tobytes())
    back = read_contour_map(tmp_path / "be.ply")
    assert back.has_edge_normals and back.edge_normal.dtype.isnative
    np.testing.assert_array_equal(back.points, cm.points)
    np.testing.assert_array_equal(back.edge_normal, cm.edge_normal.astype(np.float32))
    np.testing.assert_array_equal(back.region_id, cm.region_id)
    np.testing.assert_array_equal(back.brightness_sign, cm.brightness_sign)


def test_an_unknown_ply_format_is_named(tmp_path):
    import pytest

    from evpose.errors import InputError
    from evpose.io.map_ply import read_contour_map

    (tmp_path / "m.ply").write_text("ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0000000000000")
    with pytest.raises(InputError, match="m.ply: unknown PLY format 'binary_middle_endian'"):
        read_contour_map(tmp_path / "m.ply")
