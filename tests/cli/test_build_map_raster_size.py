"""``evpose build-map``: a raster cell too fine for the cloud's extent is refused before building, from a flag or a
config file (1e-9 m passed the field's 0..0.2 m range and the contour rasters never finished)."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.mapping.build import MAX_RASTER_CELLS, MapBuildConfig, MapBuildError, build_contour_map, check_raster
from evpose.cli.main import run


def _cloud(tmp_path, extent: float = 30.0):
    """An ascii PLY spanning ``extent`` x ``extent`` m."""
    pts = np.random.default_rng(0).uniform(0, extent, size=(200, 3)) * [1, 1, 0.01]
    pts[:2] = [[0, 0, 0], [extent, extent, 0]]
    path = tmp_path / "cloud.ply"
    header = f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    path.write_text(header + "".join(f"{x} {y} {z}\n" for x, y, z in pts))
    return path


@pytest.mark.parametrize("how", ["flag", "config"])
def test_a_cell_too_fine_for_the_cloud_is_one_line_and_writes_nothing(tmp_path, capsys, how):
    cloud = _cloud(tmp_path)
    out = tmp_path / "map.ply"
    if how == "flag":
        args = ["--cell", "1e-9"]
    else:
        (tmp_path / "build.yaml").write_text("cell_m: 1.0e-9\n")
        args = ["--config", str(tmp_path / "build.yaml")]
    assert run(["build-map", str(cloud), "--out", str(out), "--quiet", *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{cloud}: cell_m 1e-09 m would raster the cloud's 30.0 x 30.0 m into" in err
    assert "give a coarser --cell, or 0 for the automatic one" in err and not out.exists()


def test_the_bound_is_on_the_raster_not_the_cell():
    pts = np.array([[0.0, 0.0, 0.0], [30.0, 30.0, 1.0]])
    check_raster(pts, 0.0)  # automatic: checked once the spacing is known
    check_raster(pts, 0.005)  # 3.6e7 cells: 58 s on the landing cloud, allowed
    with pytest.raises(MapBuildError, match="into 2.3e\\+08 cells"):
        check_raster(pts, 0.002)
    check_raster(pts / 10, 0.0005)  # a 3 m scene takes a 10x finer cell
    assert MAX_RASTER_CELLS == 5e7



def test_the_library_refuses_a_given_cell_too_fine_before_any_work():
    # The guard sits in build_contour_map, so callers other than the command get it too (a 1e-9 m cell never finished).
    pts = np.random.default_rng(0).uniform(0, 30.0, size=(200, 3)) * [1, 1, 0.01]
    with pytest.raises(MapBuildError, match="cell_m 1e-09 m would raster the cloud's"):
        build_contour_map(pts, config=MapBuildConfig(cell_m=1e-9))
