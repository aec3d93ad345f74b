"""``evpose info`` on recordings of every format, contour maps and TUM trajectories."""

import json

import numpy as np
import pytest

from evpose.cli.main import run
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.io.ecd import write_ecd_folder
from evpose.io.map_ply import write_contour_map
from evpose.io.tum import write_tum


def info(capsys, *args):
    capsys.readouterr()
    code = run(["info", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_ecd_folder_without_size_says_the_size_is_unknown(tmp_path, capsys):
    t = np.arange(0, 1_000_000, 100)
    write_ecd_folder(tmp_path / "s", Recording(EventArray.from_arrays(t, t % 200, t % 100, t % 2)))
    (tmp_path / "s" / "evpose.json").unlink()
    (tmp_path / "s" / "calib.txt").write_text("1 2 3 4 0 0 0 0 0\n")
    code, out, _ = info(capsys, tmp_path / "s")
    assert code == 0
    assert "events        10000" in out and "sensor size   unknown" in out
    assert "calib.txt has intrinsics but no sensor size" in out
    code, out, _ = info(capsys, tmp_path / "s", "--width", "240", "--height", "180", "--json-output")
    s = json.loads(out)
    assert s["sensor_size"] == [240, 180] and s["calibration"]["fx"] == 1.0
    assert s["event_rate_hz"] == pytest.approx(10000 / 0.9999)


def test_tum_trajectory_reports_poses_duration_and_path_length(tmp_path, capsys):
    t = np.arange(11) * 100_000
    pos = np.stack([np.arange(11) * 0.1, np.zeros(11), np.zeros(11)], axis=1)
    write_tum(tmp_path / "traj.txt", Trajectory.from_arrays(t, pos, np.tile([0, 0, 0, 1.0], (11, 1))))
    code, out, _ = info(capsys, tmp_path / "traj.txt", "--json-output")
    s = json.loads(out)
    assert (s["poses"], s["duration_s"]) == (11, 1.0)
    assert s["path_length_m"] == pytest.approx(1.0)


def test_contour_map_reports_points_bounds_regions_and_attributes(tmp_path, capsys):
    pts = np.array([[0, 0, 0], [1, 2, 3], [-1, 0, 1.0]])
    cmap = ContourMap.from_points(pts, region_id=[0, 0, 1], edge_normal=[[1, 0, 0]] * 3, brightness_sign=[1, 0, -1])
    write_contour_map(tmp_path / "m.ply", cmap)
    code, out, _ = info(capsys, tmp_path / "m.ply", "--json-output")
    s = json.loads(out)
    assert s["points"] == 3 and s["regions"] == 2 and s["edge_normals"] and s["brightness_signs"]
    assert s["bounds_min_m"] == [-1, 0, 0] and s["bounds_max_m"] == [1, 2, 3]
    code, out, _ = info(capsys, tmp_path / "m.ply")
    assert "points        3" in out and "known for 66.7 % of points" in out


def test_text_file_that_is_not_a_trajectory_exits_2(tmp_path, capsys):
    (tmp_path / "x.txt").write_text("hello world\n")
    code, _, err = info(capsys, tmp_path / "x.txt")
    assert code == 2 and "not a TUM trajectory" in err


def test_evpose_h5_with_contradicting_width_height_is_a_one_line_error_naming_file_and_flags(tmp_path, capsys):
    from evpose.io.h5 import write_recording_h5

    t = np.arange(0, 100_000, 100)
    write_recording_h5(tmp_path / "r.h5", Recording(EventArray.from_arrays(t, t % 200, t % 100, t % 2), metadata={"width": 240, "height": 180}))
    code, _, err = info(capsys, tmp_path / "r.h5", "--width", "346", "--height", "260")
    assert code == 2
    assert err.strip().endswith("r.h5: --width/--height 346x260 contradict the 240x180 sensor stated by its metadata") and err.count("\n") == 1
    assert info(capsys, tmp_path / "r.h5", "--width", "240", "--height", "180")[0] == 0


def test_info_refuses_an_ecd_folder_whose_calib_txt_contradicts_its_sidecar_in_one_line(tmp_path, capsys):
    from evpose.core.camera import CameraCalibration

    t = np.arange(0, 1_000_000, 100)
    rec = Recording(EventArray.from_arrays(t, t % 200, t % 100, t % 2), calibration=CameraCalibration(240, 180, 200.0, 200.0, 120.0, 90.0))
    write_ecd_folder(tmp_path / "s", rec)
    (tmp_path / "s" / "calib.txt").write_text("210 200 120 90\n")  # edited by hand; evpose.json still says 200
    code, out, err = info(capsys, tmp_path / "s")
    assert code == 2 and out == ""
    assert err.strip() == (f"evpose info: error: {tmp_path / 's' / 'calib.txt'}: fx 210.0 contradicts the calibration in evpose.json"
                           " (fx 200.0), which is the one used: make them agree (or delete one of them)")


def test_info_names_the_longest_event_gap_when_tracking_would_restart_after_it(tmp_path, capsys):
    t = np.concatenate([np.arange(0, 500_000, 100), np.arange(7_500_000, 8_000_000, 100)])
    write_ecd_folder(tmp_path / "s", Recording(EventArray.from_arrays(t, t % 200, t % 100, t % 2)))
    code, out, _ = info(capsys, tmp_path / "s", "--width", "240", "--height", "180")
    assert code == 0
    assert "event gap     7.000100 s without events after t=0.499900 s (the longest; evpose track restarts after gaps over 1 s)" in out
    code, out, _ = info(capsys, tmp_path / "s", "--width", "240", "--height", "180", "--json-output")
    assert json.loads(out)["longest_event_gap_s"] == pytest.approx(7.0001)
    short = np.arange(0, 1_000_000, 100)
    write_ecd_folder(tmp_path / "u", Recording(EventArray.from_arrays(short, short % 200, short % 100, short % 2)))
    assert "event gap" not in info(capsys, tmp_path / "u", "--width", "240", "--height", "180")[1]
