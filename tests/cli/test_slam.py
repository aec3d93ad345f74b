import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
from slam_synthetic import make_recording  # noqa: E402

from evpose.cli.main import run  # noqa: E402
from evpose.io.h5 import write_recording_h5  # noqa: E402
from evpose.io.tum import read_tum  # noqa: E402


@pytest.fixture(scope="module")
def moving_h5(tmp_path_factory):
    path = tmp_path_factory.mktemp("slam") / "moving.h5"
    write_recording_h5(path, make_recording(duration_s=1.2, speed=1.5, seed=11))
    return path


def test_slam_cli_writes_a_tum_file_per_map_and_a_summary(moving_h5, tmp_path):
    out = tmp_path / "est.txt"
    assert run(["slam", str(moving_h5), "--out", str(out)]) == 0
    traj = read_tum(out)
    assert len(traj) >= 5
    assert read_tum(tmp_path / "est.map0.txt").t.tolist() == traj.t.tolist()
    doc = json.loads((tmp_path / "est.slam.json").read_text())
    assert doc["maps"][0]["poses"] == len(traj)
    assert doc["metrics"]["tracked_fraction"] > 0.5
    assert doc["visual_fraction"] == pytest.approx(doc["time_by_status_s"].get("ok", 0.0) / doc["duration_s"])
    assert doc["latency_ms"]["total"]["median_ms"] > 0


def test_slam_cli_reports_bad_mode_and_bad_config_in_one_line(moving_h5, tmp_path, capsys):
    assert run(["slam", str(moving_h5), "--out", str(tmp_path / "a.txt"), "--mode", "lidar"]) == 2
    assert "--mode" in capsys.readouterr().err
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("window:\n  initial_evnts: 10\n")
    assert run(["slam", str(moving_h5), "--out", str(tmp_path / "a.txt"), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "window.initial_evnts" in err and len(err.strip().splitlines()) == 1


def test_slam_cli_on_a_still_camera_says_not_initialised(tmp_path, capsys):
    path = tmp_path / "still.h5"
    write_recording_h5(path, make_recording(duration_s=0.3, still=True))
    assert run(["slam", str(path), "--out", str(tmp_path / "e.txt")]) == 1
    assert "not initialised" in capsys.readouterr().err  # status on stderr, as evpose track's
    assert not (tmp_path / "e.txt").exists()


def test_slam_cli_event_inertial_mode_needs_imu(tmp_path, capsys):
    rec = make_recording(duration_s=0.2, speed=1.5)
    rec.imu = None
    path = tmp_path / "noimu.h5"
    write_recording_h5(path, rec)
    assert run(["slam", str(path), "--out", str(tmp_path / "e.txt"), "--mode", "event-inertial"]) == 2
    err = capsys.readouterr().err.strip()
    assert "IMU" in err and str(path) in err and len(err.splitlines()) == 1


def test_slam_cli_event_inertial_mode_with_one_imu_sample_says_how_many_it_has(tmp_path, capsys):
    rec = make_recording(duration_s=0.2, speed=1.5)
    if rec.imu is None:
        pytest.skip("the synthetic SLAM recording has no IMU")
    rec.imu = rec.imu[:1]
    path = tmp_path / "one.h5"
    write_recording_h5(path, rec)
    assert run(["slam", str(path), "--out", str(tmp_path / "e.txt"), "--mode", "event-inertial"]) == 2
    err = capsys.readouterr().err.strip()
    assert "at least 2 IMU samples" in err and "has 1" in err and len(err.splitlines()) == 1


def test_slam_cli_event_inertial_mode_refuses_an_imu_on_another_clock(tmp_path, capsys):
    # IMU samples 10 s after the events: the run exited 0 and quietly went without the IMU.
    import dataclasses

    rec = make_recording(duration_s=0.2, speed=1.5)
    if rec.imu is None:
        pytest.skip("the synthetic SLAM recording has no IMU")
    rec.imu = dataclasses.replace(rec.imu, t=rec.imu.t + 10_000_000)
    path = tmp_path / "late.h5"
    write_recording_h5(path, rec)
    assert run(["slam", str(path), "--out", str(tmp_path / "e.txt"), "--mode", "event-inertial"]) == 2
    err = capsys.readouterr().err.strip()
    assert str(path) in err and "do not cover the first event" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "e.txt").exists()


def test_slam_cli_event_inertial_configuration_is_recorded_and_checked(moving_h5, tmp_path, capsys):
    out = tmp_path / "ei.txt"
    assert run(["slam", str(moving_h5), "--out", str(out), "--mode", "event-inertial", "--configuration", "c1"]) == 0
    doc = json.loads((tmp_path / "ei.slam.json").read_text())
    assert doc["config"]["mode"] == "event-inertial" and doc["config"]["inertial"]["configuration"] == "c1"
    cfg = tmp_path / "c3.yaml"
    cfg.write_text("inertial:\n  configuration: c3\n")
    assert run(["slam", str(moving_h5), "--out", str(out), "--mode", "event-inertial", "--config", str(cfg)]) == 0
    assert json.loads((tmp_path / "ei.slam.json").read_text())["config"]["inertial"]["configuration"] == "c3"
    assert run(["slam", str(moving_h5), "--out", str(out), "--configuration", "c9"]) == 2
    assert "--configuration" in capsys.readouterr().err


def test_slam_onto_its_input_refuses_before_running_and_leaves_no_map_files(moving_h5, tmp_path, capsys):
    # The per-map EST.map0 file used to be written before --out was refused.
    import shutil

    rec = tmp_path / "in.h5"
    shutil.copy(moving_h5, rec)
    assert run(["slam", str(rec), "--out", str(rec)]) == 2
    err = capsys.readouterr().err.strip()
    assert "refusing to overwrite an input file" in err and len(err.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.h5"]


def _files(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_slam_interrupted_between_its_outputs_leaves_the_earlier_set_and_no_temporary_file(moving_h5, tmp_path, monkeypatch, capsys):
    import evpose.io.tum as tum

    out = tmp_path / "est.txt"
    assert run(["slam", str(moving_h5), "--out", str(out)]) == 0
    before = _files(tmp_path)
    calls = []
    write_tum = tum.write_tum

    def interrupted_after_one(path, traj, inputs=()):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        write_tum(path, traj, inputs)

    monkeypatch.setattr(tum, "write_tum", interrupted_after_one)
    assert run(["slam", str(moving_h5), "--out", str(out)]) == 130
    assert "interrupted" in capsys.readouterr().err
    # Not one new map beside the earlier run's summary (which differs from run to run: its wall times).
    assert _files(tmp_path) == before


def test_slam_removes_an_earlier_runs_surplus_map_files(moving_h5, tmp_path):
    out = tmp_path / "est.txt"
    assert run(["slam", str(moving_h5), "--out", str(out)]) == 0
    n = len(json.loads((tmp_path / "est.slam.json").read_text())["maps"])
    for k in (n, n + 1):  # what a run with more maps left; `evpose eval --atlas` would read them as this run's
        (tmp_path / f"est.map{k}.txt").write_text("# an earlier run's map\n")
    assert run(["slam", str(moving_h5), "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.glob("est.map*.txt")) == [f"est.map{k}.txt" for k in range(n)]


def test_slam_terminated_while_its_outputs_are_renamed_exits_143_with_the_whole_set(moving_h5, tmp_path, monkeypatch, capsys):
    import os
    import signal

    from evpose.io import atomic

    publish = atomic._publish
    renamed = []

    def publish_then_terminate(tmp, dst, is_dir):
        if not renamed:
            os.kill(os.getpid(), signal.SIGTERM)  # `kill` after the first rename: acted on once the set is in place
        renamed.append(dst.name)
        publish(tmp, dst, is_dir)

    monkeypatch.setattr(atomic, "_publish", publish_then_terminate)
    assert run(["slam", str(moving_h5), "--out", str(tmp_path / "est.txt")]) == 143
    assert "terminated" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(renamed) and "est.slam.json" in renamed and len(renamed) >= 3


def test_slam_never_removes_an_input_named_like_a_surplus_map_file(tmp_path):
    from evpose.cli.slam import stale_outputs

    out = tmp_path / "est.txt"
    for k in (1, 2):
        (tmp_path / f"est.map{k}.txt").write_text("x\n")
    assert stale_outputs(out, 1) == [tmp_path / "est.map1.txt", tmp_path / "est.map2.txt"]
    assert stale_outputs(out, 1, inputs=(tmp_path / "est.map2.txt",)) == [tmp_path / "est.map1.txt"]


@pytest.mark.parametrize("command", ["slam", "track"])
def test_an_ecd_folder_with_calib_txt_but_no_sensor_size_says_to_pass_it(tmp_path, capsys, command):
    # The same bare "no camera calibration" as a folder without any, though --width/--height was all it lacked.
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("0.1 1 2 1\n0.2 3 4 0\n")
    (d / "calib.txt").write_text("200 200 119.5 89.5\n")
    extra = ["--map", str(tmp_path / "m.ply"), "--no-progress"] if command == "track" else []
    if command == "track":
        import numpy as np

        from evpose.core.contour_map import ContourMap
        from evpose.io.map_ply import write_contour_map

        write_contour_map(tmp_path / "m.ply", ContourMap.from_points(np.zeros((3, 3))))
    assert run([command, str(d), "--out", str(tmp_path / "o.txt"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no camera calibration (its calib.txt has intrinsics but no sensor size: pass --width/--height)" in err[0]
