"""TUM-VIE / VECtor / DSEC event h5 files with their sibling calibration and ground truth."""

import json

import h5py
import hdf5plugin
import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from io_factory import make_recording
from evpose.core.camera import DistortionModel
from evpose.core.events import EventArray
from evpose.errors import InputError
from evpose.io.event_h5 import EventH5Reader, write_event_h5
from evpose.io.open import SourceFormat, detect_format, open_recording
from evpose.io.tum import write_tum


def test_dsec_style_file_with_blosc_zstd_and_offset_round_trips(tmp_path):
    rec = make_recording(n=5000, width=640, height=480)
    path = tmp_path / "events.h5"
    write_event_h5(path, rec.events, t_offset_us=rec.t_start_us - 17, compression=hdf5plugin.Blosc(cname="zstd", clevel=3))
    assert detect_format(path) is SourceFormat.EVENT_H5
    back = open_recording(path)
    for c in "txyp":
        np.testing.assert_array_equal(getattr(back.events, c), getattr(rec.events, c))
    assert back.sensor_size is None and back.metadata["t_offset_us"] == rec.t_start_us - 17


_REC = make_recording(n=4000, seed=5, duration_us=30_000)


@pytest.fixture(scope="module")
def dsec(tmp_path_factory):
    path = tmp_path_factory.mktemp("dsec") / "events.h5"
    write_event_h5(path, _REC.events, t_offset_us=_REC.t_start_us - 1234)
    return path


@settings(max_examples=40, deadline=None)
@given(st.integers(_REC.t_start_us - 2000, _REC.t_end_us + 2000), st.integers(0, 35_000))
def test_windowed_read_through_ms_to_idx_equals_slicing(dsec, t0, length):
    with EventH5Reader(dsec) as r:
        got = r.read_events(t0, t0 + length)
    np.testing.assert_array_equal(got.t, _REC.events.time_window(t0, t0 + length).t)


def test_tum_vie_layout_reads_basalt_calibration_and_mocap(tmp_path):
    rec = make_recording(n=2000, width=1280, height=720)
    write_event_h5(tmp_path / "mocap-desk-events_left.h5", rec.events, with_ms_to_idx=False)
    intr = {"camera_type": "kb4", "intrinsics": {"fx": 1050.0, "fy": 1049.0, "cx": 640.5, "cy": 360.2, "k1": 0.01, "k2": -0.002, "k3": 0.0005, "k4": -0.0001}}
    calib = {"value0": {"intrinsics": [intr, intr], "resolution": [[1280, 720], [1280, 720]], "T_imu_cam": [{"px": 0.1, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}] * 2}}
    (tmp_path / "camera-calibrationA.json").write_text(json.dumps(calib))
    gt = rec.ground_truth
    with open(tmp_path / "mocap_data.txt", "w") as fh:
        fh.write("# timestamp[us] tx ty tz qx qy qz qw\n")
        for t, p, q in zip(gt.t, gt.position, gt.quat_xyzw):
            fh.write(f"{t} {' '.join(repr(float(v)) for v in p)} {' '.join(repr(float(v)) for v in q)}\n")
    imu = rec.imu
    with open(tmp_path / "imu_data.txt", "w") as fh:
        fh.write("# timestamp [us] gx gy gz [rad/s] ax ay az [m/s^2] temperature\n")
        for t, g, a in zip(imu.t, imu.gyro.tolist(), imu.acc.tolist()):
            fh.write(f"{t}.0 {' '.join(map(repr, g))} {' '.join(map(repr, a))} 31.5\n")
    back = open_recording(tmp_path / "mocap-desk-events_left.h5")
    np.testing.assert_array_equal(back.imu.t, imu.t)
    np.testing.assert_array_equal(back.imu.gyro, imu.gyro)
    np.testing.assert_array_equal(back.imu.acc, imu.acc)
    cal = back.calibration
    assert (cal.width, cal.height, cal.model) == (1280, 720, DistortionModel.EQUIDISTANT)
    assert cal.dist == (0.01, -0.002, 0.0005, -0.0001)
    np.testing.assert_allclose(cal.T_cam_imu[:3, 3], [-0.1, 0, 0])
    np.testing.assert_array_equal(back.ground_truth.t, gt.t)
    np.testing.assert_array_equal(back.events.t, rec.events.t)


def test_vector_layout_reads_kalibr_yaml_and_tum_ground_truth(tmp_path):
    rec = make_recording(n=2000, width=640, height=480)
    write_event_h5(tmp_path / "corner_slow1.synced.left_event.hdf5", rec.events, t_offset_us=rec.t_start_us)
    cam0 = {"camera_model": "pinhole", "intrinsics": [327.3, 327.1, 304.9, 235.4], "distortion_model": "radtan", "distortion_coeffs": [-0.03, 0.04, 0.001, -0.002], "resolution": [640, 480], "T_cam_imu": np.eye(4).tolist(), "timeshift_cam_imu": 0.0025}
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump({"cam0": cam0}))
    write_tum(tmp_path / "corner_slow1.synced.gt.txt", rec.ground_truth)
    back = open_recording(tmp_path / "corner_slow1.synced.left_event.hdf5")
    assert back.calibration.model is DistortionModel.RADTAN and back.calibration.dist[-1] == 0.0
    assert back.calibration.time_offset_us == 2500
    assert back.metadata["ground_truth_file"] == "corner_slow1.synced.gt.txt"
    np.testing.assert_array_equal(back.ground_truth.t, rec.ground_truth.t)


def test_events_outside_the_stated_sensor_are_named(tmp_path):
    ev = EventArray.from_arrays([1, 2, 3], [5, 700, 5], [5, 5, 5], [1, 0, 1])
    write_event_h5(tmp_path / "events.h5", ev)
    with pytest.raises(InputError, match="events.h5: event 1: x=700 is outside the sensor width 640"):
        open_recording(tmp_path / "events.h5", 640, 480)


def test_unsorted_and_bad_polarity_events_are_named(tmp_path):
    write_event_h5(tmp_path / "u.h5", EventArray.from_arrays([1, 5, 3], [0, 0, 0], [0, 0, 0], [1, 0, 1]), with_ms_to_idx=False)
    with pytest.raises(InputError, match="u.h5: event 2: timestamp 3 us is earlier"):
        open_recording(tmp_path / "u.h5")
    with h5py.File(tmp_path / "p.h5", "w") as f:
        for c, v in (("x", [0, 0]), ("y", [0, 0]), ("t", [0, 1]), ("p", [1, 7])):
            f[f"events/{c}"] = np.array(v)
    with pytest.raises(InputError, match="p.h5: event 1: polarity 7"):
        open_recording(tmp_path / "p.h5")


def test_h5_without_the_events_layout_names_what_is_missing(tmp_path):
    with h5py.File(tmp_path / "a.h5", "w") as f:
        f["foo"] = 1
    with pytest.raises(InputError, match="no 'events' group"):
        open_recording(tmp_path / "a.h5")
    with h5py.File(tmp_path / "b.h5", "w") as f:
        f["events/x"] = np.zeros(3)
    with pytest.raises(InputError, match="missing dataset"):
        open_recording(tmp_path / "b.h5")
    with h5py.File(tmp_path / "c.h5", "w") as f:
        for c in "xytp":
            f[f"events/{c}"] = np.zeros(0)
    with pytest.raises(InputError, match="contains no events"):
        open_recording(tmp_path / "c.h5")


def test_bad_sibling_calibration_is_named(tmp_path):
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump({"cam0": {"intrinsics": [1, 2, 3], "resolution": [640, 480]}}))
    with pytest.raises(InputError, match="camchain.yaml: cam0: not a kalibr camera calibration"):
        open_recording(tmp_path / "e.h5")


def test_nan_timestamp_in_a_float_time_column_is_named_without_numpy_warnings(tmp_path):
    import warnings

    with h5py.File(tmp_path / "f.h5", "w") as f:
        for c, v in (("x", [0, 0, 0]), ("y", [0, 0, 0]), ("t", [0.0, np.nan, 2.0]), ("p", [1, 0, 1])):
            f[f"events/{c}"] = np.array(v)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's cast warning was printed before the error
        with pytest.raises(InputError, match=r"f.h5: event 1: timestamp nan is not a finite number"):
            open_recording(tmp_path / "f.h5", 640, 480)


@pytest.mark.parametrize("name, text, message", [
    ("camchain.yaml", yaml.safe_dump({"cam0": {"intrinsics": [float("nan"), 2, 3, 4], "resolution": [640, 480]}}),
     "camchain.yaml: cam0: calibration has NaN or infinite values"),
    ("camera-calibration.json", json.dumps({"value0": {"intrinsics": [{"camera_type": "pinhole", "intrinsics": {"fx": -5, "fy": 5, "cx": 320, "cy": 240}}],
                                                       "resolution": [[640, 480]]}}),
     "camera-calibration.json: calibration needs positive size and focal lengths"),
])
def test_invalid_values_in_a_sibling_calibration_name_the_file(tmp_path, name, text, message):
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    (tmp_path / name).write_text(text)
    with pytest.raises(InputError, match=message):
        open_recording(tmp_path / "e.h5")


def test_sensor_size_flags_that_contradict_the_sibling_calibration_name_file_and_flags(tmp_path):
    rec = make_recording(n=200, duration_us=20_000)
    write_event_h5(tmp_path / "seq-events_left.h5", rec.events)
    intr = {"camera_type": "pinhole", "intrinsics": {"fx": 200.0, "fy": 200.0, "cx": 119.5, "cy": 89.5}}
    (tmp_path / "camera-calibration.json").write_text(json.dumps({"value0": {"intrinsics": [intr], "resolution": [[240, 180]]}}))
    assert open_recording(tmp_path / "seq-events_left.h5", 240, 180).sensor_size == (240, 180)
    with pytest.raises(InputError, match=r"seq-events_left.h5: --width/--height 346x260 contradict the 240x180 sensor stated by the calibration camera-calibration.json"):
        open_recording(tmp_path / "seq-events_left.h5", 346, 260)


@pytest.mark.parametrize("offset, got", [(np.float64(np.nan), "got nan"), (np.arange(3), "got 3 values"), (np.bytes_(b"soon"), "got b'soon'")])
def test_a_t_offset_that_is_not_one_number_is_named(tmp_path, offset, got):
    # NaN ended in a ValueError traceback, an array silently gave its first value.
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1, 2], [0, 1], [0, 1], [1, -1]))
    with h5py.File(tmp_path / "e.h5", "r+") as f:
        del f["t_offset"]
        f["t_offset"] = offset
    with pytest.raises(InputError, match=rf"e.h5: t_offset must be one finite number of microseconds, {got}"):
        open_recording(tmp_path / "e.h5", 640, 480)


@pytest.mark.parametrize("damage", ["reversed", "beyond"])
def test_a_damaged_ms_to_idx_is_named_not_trusted_by_windowed_reads(tmp_path, damage):
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays(np.arange(0, 5000, 10), np.zeros(500), np.zeros(500), np.ones(500)))
    with h5py.File(tmp_path / "e.h5", "r+") as f:
        idx = f["ms_to_idx"][()]
        del f["ms_to_idx"]
        f["ms_to_idx"] = idx[::-1].copy() if damage == "reversed" else idx + 1000
    with pytest.raises(InputError, match=r"e.h5: ms_to_idx is not a non-decreasing index into the 500 events"):
        EventH5Reader(tmp_path / "e.h5")


@pytest.mark.parametrize("column, data, message", [
    # A string, scalar or compound column ended in a ValueError, IndexError or TypeError traceback.
    ("t", np.array([b"a", b"b"]), r"events/t is dtype \|S1, shape \(2,\), expected a 1-D column of numbers"),
    ("t", np.int64(5), r"events/t is dtype int64, shape \(\), expected a 1-D column of numbers"),
    ("x", np.zeros(2, dtype=[("a", "i8"), ("b", "i8")]), r"events/x is dtype .*, expected a 1-D column of numbers"),
    # A float pixel of 3.7 was truncated to 3 silently; NaN was cast to 0 with numpy's warning.
    ("x", np.array([1.0, 3.7]), r"event 1: x=3.7 is not a pixel coordinate"),
    ("y", np.array([np.nan, 1.0]), r"event 0: y=nan is not a pixel coordinate"),
])
def test_event_columns_that_are_not_whole_pixel_numbers_are_named(tmp_path, column, data, message):
    import warnings

    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1, 2], [0, 1], [0, 1], [1, -1]))
    with h5py.File(tmp_path / "e.h5", "r+") as f:
        del f[f"events/{column}"]
        f[f"events/{column}"] = data
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match=message):
            open_recording(tmp_path / "e.h5", 640, 480)


def test_a_float_ms_to_idx_holding_nan_is_named_without_numpy_warnings(tmp_path):
    import warnings

    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1, 2], [0, 1], [0, 1], [1, -1]))
    with h5py.File(tmp_path / "e.h5", "r+") as f:
        del f["ms_to_idx"]
        f["ms_to_idx"] = np.array([0.0, np.nan])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "invalid value encountered in cast" was printed
        with pytest.raises(InputError, match=r"e.h5: ms_to_idx is not a non-decreasing index into the 2 events"):
            EventH5Reader(tmp_path / "e.h5")


@pytest.mark.parametrize("name, message", [
    # Skipped as if absent (no IMU, no ground truth), or an IsADirectoryError traceback for the calibration.
    ("camera-calibration.json", "camera-calibration.json: is a folder, not a file"),
    ("mocap_data.txt", "mocap_data.txt: is a folder, not a file"),
    ("imu_data.txt", "imu_data.txt: is a folder, not a file"),
])
def test_a_folder_in_place_of_a_sibling_file_is_named(tmp_path, name, message):
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    (tmp_path / name).mkdir()
    with pytest.raises(InputError, match=message):
        open_recording(tmp_path / "e.h5", 640, 480)


@pytest.mark.parametrize("shift, message", [
    (".inf", "not a kalibr camera calibration \\(OverflowError"),  # was an OverflowError traceback
    ("1e300", "calibration's time_offset_us 100000000000000001721... is not a number of microseconds within"),
])
def test_a_kalibr_timeshift_beyond_any_clock_is_named(tmp_path, shift, message):
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    cam = "cam0:\n  intrinsics: [200, 200, 119.5, 89.5]\n  resolution: [240, 180]\n"
    (tmp_path / "camchain.yaml").write_text(cam + f"  timeshift_cam_imu: {shift}\n")
    with pytest.raises(InputError, match=f"camchain.yaml: cam0: {message}"):
        open_recording(tmp_path / "e.h5")


def test_an_event_column_with_unwritten_chunks_is_named(tmp_path):
    # A converter that sized its columns first and stopped leaves chunks that read as zeros.
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1, 2], [0, 1], [0, 1], [1, -1]))
    with h5py.File(tmp_path / "e.h5", "r+") as f:
        for c in "xytp":
            del f[f"events/{c}"]
            f.create_dataset(f"events/{c}", shape=(10**9,), dtype="u2" if c in "xy" else "i8", chunks=(1 << 16,))
        f["events/t"][:10] = np.arange(10)
    with pytest.raises(InputError, match=r"e.h5: events/t has 1 of its 15259 chunks written: the file is damaged"):
        EventH5Reader(tmp_path / "e.h5")


def test_a_truncated_kalibr_yaml_names_its_line_in_one_short_message(tmp_path):
    # The parser's whole report ("in "<unicode string>", line 2, column 15: intrinsics: [...") was quoted.
    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    (tmp_path / "camchain.yaml").write_text("cam0:\n  intrinsics: [200, 200, 119.5")
    with pytest.raises(InputError) as info:
        open_recording(tmp_path / "e.h5")
    assert str(info.value) == f"{tmp_path / 'camchain.yaml'}: line 2: not valid YAML (expected ',' or ']', but got '<stream end>')"


@pytest.mark.parametrize("name", ["camera-calibration.json", "camchain.yaml", "imu_data.txt", "mocap_data.txt"])
def test_a_named_pipe_in_place_of_a_sibling_file_is_refused_at_once(tmp_path, name):
    # Reading it waited for a writer forever.
    import os

    write_event_h5(tmp_path / "e.h5", EventArray.from_arrays([1], [0], [0], [1]))
    os.mkfifo(tmp_path / name)
    with pytest.raises(InputError, match=f"{name}: is not a regular file"):
        open_recording(tmp_path / "e.h5", 640, 480)
