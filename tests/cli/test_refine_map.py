"""``evpose refine-map``: writes a refined map beside its inputs, never over them; one-line errors."""

import dataclasses
import json

import numpy as np
import pytest

from evpose.cli.main import run
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import read_contour_map, write_contour_map


@pytest.fixture(scope="module")
def landing_files(sim_landing_small, tmp_path_factory):
    """0.3 s of the small simulated landing (with IMU) and a map along its true edges, with edge normals."""
    from evpose.bench.registration_bias import true_edge_points
    from evpose.core.contour_map import ContourMap

    rec = sim_landing_small.recording
    rec = dataclasses.replace(rec, events=rec.events.time_window(int(rec.events.t[0]), int(rec.events.t[0]) + 300_000))
    d = tmp_path_factory.mktemp("refine_map")
    write_recording_h5(d / "rec.h5", rec)
    pts = true_edge_points(sim_landing_small.edges, step_m=0.02)
    n = pts.shape[0]
    write_contour_map(d / "bare.ply", ContourMap.from_points(pts))
    # Normals that are wrong for most edges do no harm here: the test is about the command, not the accuracy.
    cmap = ContourMap.from_points(pts, edge_normal=np.tile([1.0, 0.0, 0.0], (n, 1)),
                                  plane_normal=np.tile([0.0, 0.0, 1.0], (n, 1)), curvature=np.zeros(n))
    write_contour_map(d / "map.ply", cmap)
    return d


def test_refine_map_writes_a_map_with_the_same_points_and_a_report(landing_files, tmp_path):
    d = landing_files
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "r.ply"),
                "--report", str(tmp_path / "r.json"), "--quiet"])
    assert code == 0
    before, after = read_contour_map(d / "map.ply"), read_contour_map(tmp_path / "r.ply")
    assert len(after) == len(before)
    np.testing.assert_array_equal(after.edge_normal, before.edge_normal)
    moved = after.points - before.points
    # Points move only along their edge normal (+x here).
    np.testing.assert_allclose(moved[:, 1:], 0.0, atol=1e-12)
    report = json.loads((tmp_path / "r.json").read_text())
    assert [r["iteration"] for r in report["rounds"]] == [1]


def test_refine_map_refuses_to_overwrite_its_input(landing_files, capsys):
    d = landing_files
    before = (d / "map.ply").read_bytes()
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(d / "map.ply"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "overwrite" in err and len(err.strip().splitlines()) == 1
    assert (d / "map.ply").read_bytes() == before


def test_refine_map_without_edge_normals_is_a_one_line_error(landing_files, tmp_path, capsys):
    d = landing_files
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(d / "bare.ply"), "--out", str(tmp_path / "r.ply"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "edge normals" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "r.ply").exists()


def test_refine_map_with_a_map_in_another_frame_names_the_map_like_track(landing_files, tmp_path, capsys):
    # The error named the recording; `evpose track` names the map (with the recording), the likelier culprit.
    d = landing_files
    cmap = read_contour_map(d / "map.ply")
    write_contour_map(tmp_path / "far.ply", dataclasses.replace(cmap, points=cmap.points + 100.0))
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(tmp_path / "far.ply"), "--out", str(tmp_path / "r.ply"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith(f"evpose refine-map: error: {tmp_path / 'far.ply'}: only 0 map points are in view") and "(recording " in err[0]


@pytest.mark.parametrize("iterations", ["0", "1000000"])
def test_refine_map_iterations_outside_their_range_are_refused_before_tracking(landing_files, tmp_path, capsys, iterations):
    # 1000000 rounds tracked the recording on and on (each round a whole track): a hang, not an error.
    d = landing_files
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "r.ply"), "--quiet",
                "--iterations", iterations])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.endswith(f"--iterations must be within 1..20, got {iterations}") and len(err.splitlines()) == 1
    assert not (tmp_path / "r.ply").exists()


def test_refine_map_refuses_a_map_of_another_scene_as_track_does(landing_files, tmp_path, capsys):
    # The indoor map ran through the whole landing recording and was written back unchanged ("0 of 4 measured points
    # moved"), exit 0, where `evpose track` refused the same pairing.
    from pathlib import Path

    d = landing_files
    indoor = Path(__file__).parents[2] / "maps" / "indoor_map.ply"
    code = run(["refine-map", str(d / "rec.h5"), "--map", str(indoor), "--out", str(tmp_path / "r.ply"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and not (tmp_path / "r.ply").exists()
    assert err[0].startswith(f"evpose refine-map: error: {indoor}: updates 1-") and "is it this recording's map" in err[0]
