"""``evpose simulate``: outputs next to each other, one-line errors with exit code 2."""

import numpy as np
import pytest

from evpose.cli.main import run


def test_simulate_writes_ecd_folder_cloud_and_edges(tmp_path, capsys):
    out = tmp_path / "rec"
    code = run(["simulate", "--scenario", "landing", "--out", str(out), "--seconds", "0.03", "--resolution", "64x48", "--seed", "3", "--cloud-density", "5"])
    assert code == 0
    assert (out / "events.txt").exists() and (out / "imu.txt").exists() and (out / "groundtruth.txt").exists()
    assert (tmp_path / "rec_cloud.ply").stat().st_size > 0
    with np.load(tmp_path / "rec_edges.npz") as z:
        assert z["segments"].ndim == 3 and z["segments"].shape[1:] == (2, 3)
    assert "events" in capsys.readouterr().out


def test_simulate_writes_readable_h5(tmp_path):
    from evpose.io.h5 import read_recording_h5

    out = tmp_path / "rec.h5"
    assert run(["simulate", "--scenario", "indoor", "--out", str(out), "--seconds", "0.03", "--resolution", "64x48", "--no-cloud"]) == 0
    rec = read_recording_h5(out)
    assert len(rec.events) > 0 and rec.metadata["scenario"] == "indoor" and rec.calibration.width == 64
    assert not (tmp_path / "rec_cloud.ply").exists()


def test_simulate_flight_flies_another_path_of_the_scenario(tmp_path):
    from evpose.io.h5 import read_recording_h5

    paths = {}
    for flight in (0, 4):
        out = tmp_path / f"f{flight}.h5"
        assert run(["simulate", "--scenario", "landing", "--out", str(out), "--seconds", "0.03", "--resolution", "64x48", "--no-cloud", "--flight", str(flight)]) == 0
        paths[flight] = read_recording_h5(out)
    assert paths[4].metadata["config"]["flight"] == 4
    assert "flight" not in paths[0].metadata["config"]  # the scenario's own flight keeps its old metadata and bytes
    # A 0.03 s flight is a 9 cm spiral: the flights leave the pad's vertical in different directions.
    heading = [np.diff(paths[f].ground_truth.position[[0, -1], :2], axis=0)[0] for f in (0, 4)]
    cos = heading[0] @ heading[1] / np.linalg.norm(heading[0]) / np.linalg.norm(heading[1])
    assert cos < 0.9


@pytest.mark.parametrize(
    "args, message",
    [
        (["--scenario", "mars"], "unknown scenario"),
        (["--scenario", "landing", "--resolution", "0x0"], "impossible resolution"),
        (["--scenario", "landing", "--resolution", "346by260"], "WIDTHxHEIGHT"),
        (["--scenario", "landing", "--seconds", "-2"], "duration must be positive"),
        (["--scenario", "landing", "--cloud-density", "0"], "cloud density must be positive"),
        # 1e12 points per m^2 ended in a MemoryError traceback (22 PiB of points).
        (["--scenario", "landing", "--cloud-density", "1e12"], "--cloud-density must be within 1..5000 points/m^2, got 1e+12"),
        (["--scenario", "landing", "--range-noise", "5"], "--range-noise must be within 0..0.1 m, got 5"),
        (["--scenario", "landing", "--flight", "-1"], "flight must be non-negative"),
    ],
)
def test_bad_input_prints_one_line_and_exits_2(tmp_path, capsys, args, message):
    assert run(["simulate", "--out", str(tmp_path / "x.h5"), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err


def test_unwritable_output_exits_2(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    (locked / "file").write_text("x")
    # A path under a regular file can never be created.
    assert run(["simulate", "--scenario", "landing", "--out", str(locked / "file" / "x.h5"), "--seconds", "0.01", "--resolution", "32x24"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
