"""``evpose sweep``: a --recordings item no job could read is refused before any job, one line, exit 2."""

import numpy as np

from evpose.cli.main import run
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import write_contour_map


def _sweep(tmp_path, item):
    return run(["sweep", "rate_hz=[100]", "--recordings", item, "--out", str(tmp_path / "sw"), "--workers", "0", "--no-progress"])


def _recording(path, acc_nan=False):
    t = np.arange(0, 100_000, 100)
    ev = EventArray.from_arrays(t, t % 64, t % 48, np.ones_like(t))
    ti = np.arange(0, 100_000, 1000)
    acc = np.zeros((ti.size, 3))
    acc[3, 1] = np.nan if acc_nan else 0.0
    write_recording_h5(path, Recording(ev, ImuSamples.from_arrays(ti, acc, np.zeros((ti.size, 3))), metadata={"width": 64, "height": 48}))


def _last_error(capsys):
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "failed" not in captured.out, (captured.out, captured.err)
    return lines[0]


def test_unknown_simulated_scenario_is_refused_before_any_job(tmp_path, capsys):
    assert _sweep(tmp_path, "sim:moon") == 2
    assert _last_error(capsys).startswith("evpose sweep: error: --recordings sim:moon: unknown simulated scenario 'moon'")
    assert not (tmp_path / "sw" / "jobs").exists()


def test_damaged_hdf5_recording_is_refused_before_any_job(tmp_path, capsys):
    bad = tmp_path / "cut.h5"
    bad.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(200))
    (tmp_path / "m.ply").write_text("ply\n")
    assert _sweep(tmp_path, f"{bad}::{tmp_path / 'm.ply'}") == 2
    assert _last_error(capsys) == f"evpose sweep: error: {bad}: not an HDF5 file"


def test_nan_imu_sample_is_refused_naming_the_sample(tmp_path, capsys):
    _recording(tmp_path / "r.h5", acc_nan=True)
    (tmp_path / "m.ply").write_text("ply\n")
    assert _sweep(tmp_path, f"{tmp_path / 'r.h5'}::{tmp_path / 'm.ply'}") == 2
    assert _last_error(capsys) == f"evpose sweep: error: {tmp_path / 'r.h5'}: IMU sample 3: NaN or infinite value"


def test_bad_map_is_refused_before_any_job(tmp_path, capsys):
    _recording(tmp_path / "r.h5")
    write_contour_map(tmp_path / "m.ply", ContourMap.from_points(np.zeros((3, 3)), brightness_sign=[7, 0, 0]))
    assert _sweep(tmp_path, f"{tmp_path / 'r.h5'}::{tmp_path / 'm.ply'}") == 2
    assert _last_error(capsys) == f"evpose sweep: error: {tmp_path / 'm.ply'}: point 0: brightness_sign is 7 (expected -1, 0 or +1)"


def test_a_recording_without_its_map_is_refused_before_any_tracking_job(tmp_path, capsys):
    # Each configuration's job failed with "needs a contour map", and the sweep exited 1 after the whole grid.
    _recording(tmp_path / "r.h5")
    assert _sweep(tmp_path, str(tmp_path / "r.h5")) == 2
    assert _last_error(capsys) == (f"evpose sweep: error: --recordings {tmp_path / 'r.h5'}: tracking needs the recording's contour map:"
                                   f" pass it as {tmp_path / 'r.h5'}::MAP.ply")
    assert not (tmp_path / "sw" / "jobs").exists()
