"""open_recording recognises every format from its layout and rejects what it cannot read."""

import pytest

from io_factory import assert_same_recording, make_recording
from evpose.errors import InputError
from evpose.io.ecd import write_ecd_folder
from evpose.io.event_h5 import write_event_h5
from evpose.io.h5 import write_recording_h5
from evpose.io.open import SourceFormat, detect_format, open_recording, open_stream
from evpose.io.rosbag import write_rosbag


def test_detects_each_format(tmp_path):
    rec = make_recording(n=200, duration_us=20_000)
    write_ecd_folder(tmp_path / "ecd", rec)
    write_recording_h5(tmp_path / "r.h5", rec)
    write_event_h5(tmp_path / "e.hdf5", rec.events)
    write_rosbag(tmp_path / "b.bag", rec)
    write_rosbag(tmp_path / "b2", rec, ros2=True)
    assert detect_format(tmp_path / "ecd") is SourceFormat.ECD
    assert detect_format(tmp_path / "r.h5") is SourceFormat.EVPOSE_H5
    assert detect_format(tmp_path / "e.hdf5") is SourceFormat.EVENT_H5
    assert detect_format(tmp_path / "b.bag") is SourceFormat.ROS1_BAG
    assert detect_format(tmp_path / "b2") is SourceFormat.ROS2_BAG
    assert_same_recording(rec, open_recording(tmp_path / "ecd"))
    assert_same_recording(rec, open_recording(tmp_path / "r.h5"))


@pytest.mark.parametrize(
    "name, make, message",
    [
        ("nothing", None, "no such file or folder"),
        ("empty_dir", "dir", "neither an ECD folder"),
        ("notes.txt", "text", "unrecognised recording"),
        ("fake.h5", "text", "not an HDF5 file"),
    ],
)
def test_unrecognised_inputs_are_named(tmp_path, name, make, message):
    p = tmp_path / name
    if make == "dir":
        p.mkdir()
    elif make == "text":
        p.write_text("hello\n")
    with pytest.raises(InputError, match=message):
        open_recording(p)


def test_sensor_size_needs_both_sides_and_positive_values(tmp_path):
    from evpose.errors import ConfigError

    rec = make_recording(n=10, duration_us=1000)
    write_ecd_folder(tmp_path / "ecd", rec)
    with pytest.raises(ConfigError, match="both width and height"):
        open_recording(tmp_path / "ecd", width=240)
    with pytest.raises(ConfigError, match="1..65536"):
        open_recording(tmp_path / "ecd", width=0, height=10)


def _corrupt(path, name, index, value):
    import h5py
    import hdf5plugin  # noqa: F401 - the datasets are compressed with its filters

    with h5py.File(path, "r+") as f:
        a = f[name][...]
        a[index] = value
        f[name][...] = a


@pytest.mark.parametrize("dataset, index, value, record, message", [
    ("events/t", 101, 0, "event 101", "earlier than the previous"),
    ("events/x", 7, 300, "event 7", "outside the sensor width"),
    ("events/p", 9, 3, "event 9", "is not +1/-1"),
    ("imu/acc", (12, 1), float("nan"), "IMU sample 12", "NaN"),
    ("ground_truth/position", (4, 0), float("inf"), "pose 4", "NaN or infinite"),
])
def test_every_reader_rejects_bad_records_naming_file_and_record(tmp_path, dataset, index, value, record, message):
    from evpose.io.summary import summarize_recording

    path = tmp_path / "rec.h5"
    write_recording_h5(path, make_recording(n=2_000))
    _corrupt(path, dataset, index, value)
    for read in (open_recording, summarize_recording):  # evpose track/slam/app, and evpose info
        with pytest.raises(InputError) as exc:
            read(path)
        assert str(exc.value).startswith(f"{path}: {record}: ") and message in str(exc.value)


def test_info_of_an_evpose_h5_without_events_is_an_input_error(tmp_path):
    import dataclasses

    from evpose.core.events import EventArray
    from evpose.io.summary import summarize_recording

    path = tmp_path / "empty.h5"
    write_recording_h5(path, dataclasses.replace(make_recording(n=10), events=EventArray.empty()))
    with pytest.raises(InputError, match="empty.h5: contains no events"):
        summarize_recording(path)


def test_recording_files_lists_what_each_recording_is_read_from(tmp_path):
    from evpose.io.open import recording_files

    rec = make_recording(n=100)
    write_ecd_folder(tmp_path / "ecd", rec)
    (tmp_path / "ecd" / "notes.md").write_text("not read")
    assert [p.name for p in recording_files(tmp_path / "ecd")] == ["events.txt", "imu.txt", "groundtruth.txt", "calib.txt", "evpose.json"]
    tv = tmp_path / "tv"
    tv.mkdir()
    write_event_h5(tv / "seq-events_left.h5", rec.events)
    for name in ("camera-calibrationA.json", "mocap_data.txt", "imu_data.txt", "est.txt"):
        (tv / name).write_text("")
    assert [p.name for p in recording_files(tv / "seq-events_left.h5")] == ["camera-calibrationA.json", "mocap_data.txt", "imu_data.txt"]
    write_recording_h5(tmp_path / "r.h5", rec)
    assert recording_files(tmp_path / "r.h5") == [] and recording_files(tmp_path / "map.ply") == []


def _write_each_format(tmp_path, with_calibration):
    rec = make_recording(n=200, duration_us=20_000, with_calibration=with_calibration)  # 240x180
    write_ecd_folder(tmp_path / "ecd", rec)
    write_recording_h5(tmp_path / "r.h5", rec)
    write_rosbag(tmp_path / "b.bag", rec)
    write_rosbag(tmp_path / "b2", rec, ros2=True)
    return rec


@pytest.mark.parametrize("with_calibration", [True, False])
@pytest.mark.parametrize("name, named", [("ecd", "ecd/evpose.json"), ("r.h5", "r.h5"), ("b.bag", "b.bag"), ("b2", "b2")])
def test_sensor_size_flags_that_contradict_the_recording_are_an_error_naming_file_and_flags(tmp_path, name, named, with_calibration):
    _write_each_format(tmp_path, with_calibration)
    with pytest.raises(InputError, match=rf"{named}: --width/--height 346x260 contradict the 240x180 sensor stated by") as exc:
        open_recording(tmp_path / name, width=346, height=260)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("name", ["ecd", "r.h5", "b.bag", "b2"])
def test_sensor_size_flags_that_agree_with_the_recording_are_accepted(tmp_path, name):
    rec = _write_each_format(tmp_path, True)
    back = open_recording(tmp_path / name, width=240, height=180)
    assert back.sensor_size == (240, 180)
    assert (back.events.x == rec.events.x).all() and (back.events.t == rec.events.t).all()


def test_a_stray_far_future_event_is_refused_by_every_reader_not_tracked_through(tmp_path):
    # `convert` refused it (the HDF5 index's span); `track` read the ECD folder and ran updates through 11 days.
    rec = make_recording(n=500, duration_us=100_000)
    write_ecd_folder(tmp_path / "seq", rec)
    with open(tmp_path / "seq" / "events.txt", "a") as fh:
        fh.write("1000000.0 5 5 1\n")
    with pytest.raises(InputError, match=r"seq: event 500: events span 277.8 hours \(from \d+ to 1000000000000 us\); timestamps look wrong"):
        open_recording(tmp_path / "seq")
    with pytest.raises(InputError, match=r"seq: event 500: events span 277.8 hours"):  # `info` and `convert` stream it
        list(open_stream(tmp_path / "seq").batches(None))


def test_an_ecd_events_file_given_for_its_recording_points_to_the_folder(tmp_path):
    # "unrecognised recording (suffix '.txt')" left the user guessing what to pass instead.
    from evpose.errors import InputError
    from evpose.io.open import detect_format

    (tmp_path / "ecd").mkdir()
    (tmp_path / "ecd" / "events.txt").write_text("0.1 1 2 1\n")
    with pytest.raises(InputError, match=r"events.txt: an ECD recording is its folder \(events.txt, imu.txt...\): give .*ecd$"):
        detect_format(tmp_path / "ecd" / "events.txt")


def test_a_named_pipe_given_as_an_input_is_refused_at_once(tmp_path):
    # Reading its magic bytes waited for a writer forever; the map and table readers called it "no such file".
    import os

    from evpose.errors import InputError
    from evpose.io.map_ply import read_contour_map
    from evpose.io.open import detect_format
    from evpose.io.text_table import read_table

    os.mkfifo(tmp_path / "rec.h5")
    with pytest.raises(InputError, match="rec.h5: is not a regular file"):
        detect_format(tmp_path / "rec.h5")
    for reader in (read_contour_map, lambda p: read_table(p, 8)):
        with pytest.raises(InputError, match="rec.h5: is not a regular file"):
            reader(tmp_path / "rec.h5")
