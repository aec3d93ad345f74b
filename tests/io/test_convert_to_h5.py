"""Streaming conversion to evpose HDF5 from every source; failures leave nothing behind."""

import numpy as np
import pytest

from io_factory import assert_same_recording, make_recording
from evpose.errors import InputError
from evpose.io.convert import convert_to_h5
from evpose.io.ecd import write_ecd_folder
from evpose.io.event_h5 import write_event_h5
from evpose.io.h5 import read_recording_h5, write_recording_h5
from evpose.io.rosbag import write_rosbag


def test_ecd_folder_converts_exactly(tmp_path, recording):
    write_ecd_folder(tmp_path / "ecd", recording)
    res = convert_to_h5(tmp_path / "ecd", tmp_path / "o.h5", progress=False)
    assert res.events == len(recording.events) and res.source_format == "ecd"
    back = read_recording_h5(tmp_path / "o.h5")
    assert_same_recording(recording, back, metadata=False)
    assert back.metadata["scenario"] == "unit-test"


def test_plain_ecd_with_stated_size_gets_calibration_from_calib_txt(tmp_path):
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("0.000001 1 2 1\n0.000002 3 4 0\n")
    (d / "calib.txt").write_text("199 198 120 90 -0.3 0.1 0 0 0\n")
    convert_to_h5(d, tmp_path / "o.h5", 240, 180, progress=False)
    back = read_recording_h5(tmp_path / "o.h5")
    assert back.sensor_size == (240, 180) and back.calibration.fx == 199
    assert back.metadata["source_format"] == "ecd"


@pytest.mark.parametrize("kind", ["ros1", "ros2", "event-h5", "h5"])
def test_other_sources_convert_their_events(tmp_path, kind):
    rec = make_recording(n=3000, duration_us=300_000)
    src = tmp_path / {"ros1": "b.bag", "ros2": "b2", "event-h5": "e.h5", "h5": "r.h5"}[kind]
    if kind.startswith("ros"):
        write_rosbag(src, rec, ros2=kind == "ros2", events_per_message=256)
    elif kind == "event-h5":
        write_event_h5(src, rec.events)
    else:
        write_recording_h5(src, rec)
    convert_to_h5(src, tmp_path / "o.h5", progress=False)
    np.testing.assert_array_equal(read_recording_h5(tmp_path / "o.h5").events.t, rec.events.t)


def test_bad_line_aborts_and_leaves_no_output(tmp_path):
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("".join(f"0.{i:06d} 1 2 1\n" for i in range(1000)) + "0.9 1 2 5\n")
    with pytest.raises(InputError, match="line 1001: polarity is not 0 or 1"):
        convert_to_h5(d, tmp_path / "o.h5", progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ecd"]


def test_refuses_to_convert_onto_the_input(tmp_path, recording):
    write_recording_h5(tmp_path / "r.h5", recording)
    with pytest.raises(InputError, match="refusing to overwrite"):
        convert_to_h5(tmp_path / "r.h5", tmp_path / "r.h5", progress=False)
    assert len(read_recording_h5(tmp_path / "r.h5").events) == len(recording.events)


def test_output_is_bit_identical_across_runs_and_threading(tmp_path, recording):
    write_ecd_folder(tmp_path / "ecd", recording)
    convert_to_h5(tmp_path / "ecd", tmp_path / "a.h5", progress=False, threaded=True)
    convert_to_h5(tmp_path / "ecd", tmp_path / "b.h5", progress=False, threaded=False)
    assert (tmp_path / "a.h5").read_bytes() == (tmp_path / "b.h5").read_bytes()
