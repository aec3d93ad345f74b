"""``evpose convert``: ECD folder -> HDF5 end to end, and every bad input exits 2 with one line."""

import json
import subprocess
import sys

import numpy as np
import pytest

from evpose.cli.main import run
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.io.ecd import write_ecd_folder
from evpose.io.h5 import read_recording_h5


def ecd_folder(path, n=3000, seed=0):
    rng = np.random.default_rng(seed)
    ev = EventArray.from_arrays(np.sort(rng.integers(0, 2_000_000, n)), rng.integers(0, 240, n), rng.integers(0, 180, n), rng.integers(0, 2, n))
    write_ecd_folder(path, Recording(ev))
    (path / "evpose.json").unlink()  # a plain ECD folder, as downloaded
    (path / "calib.txt").write_text("199.09 198.70 132.19 110.71 -0.368 0.150 -0.0003 -0.0003 0.0\n")
    (path / "imu.txt").write_text("".join(f"{i / 1000:.6f} 0 0 9.81 0 0 0\n" for i in range(2000)))
    (path / "groundtruth.txt").write_text("".join(f"{i / 200:.6f} {i} 0 0 0 0 0 1\n" for i in range(400)))
    return ev


def test_convert_then_info_report_the_right_counts(tmp_path, capsys):
    ev = ecd_folder(tmp_path / "shapes")
    assert run(["convert", str(tmp_path / "shapes"), str(tmp_path / "out.h5"), "--width", "240", "--height", "180", "--quiet"]) == 0
    rec = read_recording_h5(tmp_path / "out.h5")
    np.testing.assert_array_equal(rec.events.t, ev.t)
    assert rec.calibration.fx == pytest.approx(199.09) and len(rec.imu) == 2000 and len(rec.ground_truth) == 400
    capsys.readouterr()
    assert run(["info", str(tmp_path / "out.h5"), "--json-output"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["events"] == 3000 and s["sensor_size"] == [240, 180]
    assert s["imu_samples"] == 2000 and s["imu_rate_hz"] == pytest.approx(1000.0)
    assert s["ground_truth_poses"] == 400 and s["calibration"]["model"] == "radtan"
    assert s["duration_s"] == pytest.approx((ev.t[-1] - ev.t[0]) / 1e6)


BAD = [
    ("missing", None, "no such file or folder"),
    ("events.txt", "0.1 1 2 1\n0.05 1 2 1\n", "events.txt: line 2: timestamp is earlier than the previous event's"),
    ("events.txt", "0.1 1 2\n", "events.txt: line 1: expected 4 values"),
    ("events.txt", "0.1 300 2 1\n", "events.txt: line 1: x is outside the sensor width"),
    ("events.txt", "nan 1 2 1\n", "events.txt: line 1: timestamp is not a number"),
    ("events.txt", "", "events.txt: contains no events"),
    ("calib.txt", "1 2 3 4 5\n", "calib.txt: expected 9 values"),
    ("imu.txt", "0.0 0 0 inf 0 0 0\n", "imu.txt: line 1: NaN or infinite value"),
]


@pytest.mark.parametrize("name, text, message", BAD)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, name, text, message):
    src = tmp_path / "seq"
    if name != "missing":
        src.mkdir()
        (src / "events.txt").write_text("0.1 1 2 1\n")
        (src / name).write_text(text)
    code = run(["convert", str(src), str(tmp_path / "out.h5"), "--width", "240", "--height", "180", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("evpose convert: error: ") and message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out.h5").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_unknown_bag_topic_exits_2(tmp_path, capsys):
    from evpose.io.rosbag import write_rosbag

    rec = Recording(EventArray.from_arrays([1, 2], [0, 1], [0, 1], [0, 1]), metadata={"width": 4, "height": 4})
    write_rosbag(tmp_path / "b.bag", rec)
    assert run(["convert", str(tmp_path / "b.bag"), str(tmp_path / "o.h5"), "--events-topic", "/nope", "--quiet"]) == 2
    assert "unknown events topic '/nope'" in capsys.readouterr().err


def test_convert_onto_its_input_exits_2_and_keeps_the_input(tmp_path, capsys):
    ecd_folder(tmp_path / "s", n=10)
    run(["convert", str(tmp_path / "s"), str(tmp_path / "a.h5"), "--quiet"])
    before = (tmp_path / "a.h5").read_bytes()
    assert run(["convert", str(tmp_path / "a.h5"), str(tmp_path / "a.h5"), "--quiet"]) == 2
    assert (tmp_path / "a.h5").read_bytes() == before


def test_the_installed_command_prints_no_traceback(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "evpose.cli.main", "convert", str(tmp_path / "nope"), str(tmp_path / "o.h5")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"evpose convert: error: {tmp_path / 'nope'}: no such file or folder"


@pytest.mark.parametrize("name", ["out.bag", "out.txt", "ecd_out"])
def test_convert_to_a_name_that_is_not_hdf5_is_refused(tmp_path, capsys, name):
    # HDF5 was written under that name: `evpose info out.bag` then refused it as a damaged bag.
    ecd_folder(tmp_path / "s", n=10)
    assert run(["convert", str(tmp_path / "s"), str(tmp_path / name), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"evpose convert: error: {tmp_path / name}: convert writes evpose HDF5; give an output name ending in .h5"
    assert not (tmp_path / name).exists()
