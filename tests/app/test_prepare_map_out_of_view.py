"""``evpose app --prepare`` with a map out of view at the start names the map, as ``evpose track`` does."""

import dataclasses

from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import write_contour_map


def test_prepare_with_a_map_of_another_place_names_the_map_in_one_line(tmp_path, capsys, squares_scene):
    from evpose.cli.main import run

    rec, cmap = squares_scene
    rec_path, map_path = tmp_path / "squares.h5", tmp_path / "elsewhere_map.ply"
    write_recording_h5(rec_path, rec)
    write_contour_map(map_path, dataclasses.replace(cmap, points=cmap.points + [500.0, 0.0, 0.0]))  # 500 m away
    assert run(["app", "--prepare", str(rec_path), "--map", str(map_path), "--cache-dir", str(tmp_path / "cache")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"evpose app: error: {map_path}") and "map points are in view at the initial pose" in err
