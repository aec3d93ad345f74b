"""ECD text folders: round trip, sensor size rules, every bad-input case with its line."""

import numpy as np
import pytest

from io_factory import assert_same_recording
from evpose.core.camera import DistortionModel
from evpose.errors import InputError
from evpose.io.ecd import iter_ecd_events, read_ecd_events, read_ecd_folder, write_ecd_folder


def test_round_trip_through_our_folder_is_lossless(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    assert_same_recording(recording, read_ecd_folder(tmp_path / "seq"))


def test_plain_ecd_folder_without_size_has_no_calibration_but_keeps_calib_values(tmp_path):
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("0.000000000 10 20 1\n0.000001000 11 21 0\n")
    (d / "calib.txt").write_text("199.09 198.70 132.19 110.71 -0.368 0.150 -0.0003 -0.0003 0.0\n")
    (d / "imu.txt").write_text("0.0 0 0 9.81 0 0 0\n0.001 0 0 9.81 0 0 0.1\n")
    (d / "groundtruth.txt").write_text("0.0 1 2 3 0 0 0 1\n0.01 1 2 3 0 0 0 1\n")
    rec = read_ecd_folder(d)
    assert rec.calibration is None and rec.sensor_size is None
    assert rec.metadata["ecd_calib_txt"][0] == pytest.approx(199.09)
    assert rec.events.t.tolist() == [0, 1] and rec.events.p.tolist() == [1, -1]
    assert rec.imu.t.tolist() == [0, 1000] and rec.imu.gyro[1, 2] == pytest.approx(0.1)
    assert len(rec.ground_truth) == 2
    sized = read_ecd_folder(d, 240, 180)
    assert sized.calibration.model is DistortionModel.RADTAN and sized.sensor_size == (240, 180)
    assert sized.calibration.dist[0] == pytest.approx(-0.368)


def test_timestamps_are_parsed_exactly_to_microseconds(tmp_path):
    f = tmp_path / "events.txt"
    f.write_text("1468939993.0670000 1 1 1\n1468939993.0670005 1 1 1\n1468939993.067001499 1 1 0\n1.5e-3 1 1 0\n".replace("1.5e-3", "1468939993.0670015"))
    ev = next(iter_ecd_events(f))
    assert ev.t.tolist() == [1468939993067000, 1468939993067001, 1468939993067001, 1468939993067002]


def test_exponent_notation_crlf_tabs_and_comments_are_accepted(tmp_path):
    f = tmp_path / "events.txt"
    f.write_bytes(b"# t x y p\r\n1e-6\t3  4 1\r\n\n2.5E-6 5 6 -1\n")
    ev = next(iter_ecd_events(f))
    assert ev.t.tolist() == [1, 3] and ev.x.tolist() == [3, 5] and ev.p.tolist() == [1, -1]


def test_last_line_without_newline_is_read(tmp_path):
    f = tmp_path / "events.txt"
    f.write_text("0.1 1 2 1\n0.2 3 4 0")
    assert read_ecd_events(f).t.tolist() == [100_000, 200_000]


def test_small_blocks_give_the_same_events_as_one_block(tmp_path, recording):
    write_ecd_folder(tmp_path / "s", recording)
    whole = np.concatenate([b.t for b in iter_ecd_events(tmp_path / "s" / "events.txt")])
    blocks = list(iter_ecd_events(tmp_path / "s" / "events.txt", block_bytes=4096))
    assert len(blocks) > 10
    np.testing.assert_array_equal(np.concatenate([b.t for b in blocks]), whole)
    np.testing.assert_array_equal(whole, recording.events.t)


BAD_LINES = [
    ("0.1 1 2 1\n0.2 1 2\n", "line 2: expected 4 values 't x y p', got fewer"),
    ("0.1 1 2 1 7\n", "line 1: expected 4 values 't x y p', got more"),
    ("0.1 1 2 1\nabc 1 2 1\n", "line 2: timestamp is not a number"),
    ("nan 1 2 1\n", "line 1: timestamp is not a number"),
    ("inf 1 2 1\n", "line 1: timestamp is not a number"),
    ("0.1 1.5 2 1\n", "line 1: x is not a non-negative integer"),
    ("0.1 -1 2 1\n", "line 1: x is not a non-negative integer"),
    ("0.1 1 nan 1\n", "line 1: y is not a non-negative integer"),
    ("0.1 1 2 2\n", "line 1: polarity is not 0 or 1"),
    ("0.2 1 2 1\n\n0.1 1 2 1\n", "line 3: timestamp is earlier than the previous event's"),
    ("0.1 240 2 1\n", "line 1: x is outside the sensor width"),
    ("0.1 1 180 1\n", "line 1: y is outside the sensor height"),
    ("0.1 70000 2 1\n", "line 1: x is outside the sensor width"),
    ("1e30 1 2 1\n", "line 1: timestamp is out of range"),
]


@pytest.mark.parametrize("text, message", BAD_LINES)
def test_bad_event_lines_name_file_line_and_problem(tmp_path, text, message):
    f = tmp_path / "events.txt"
    f.write_text(text)
    with pytest.raises(InputError) as err:
        list(iter_ecd_events(f, 240, 180))
    assert str(err.value).startswith(f"{f}: {message}")
    assert "\n" not in str(err.value)


def test_bad_line_far_into_the_file_is_counted_across_blocks(tmp_path):
    f = tmp_path / "events.txt"
    f.write_text("".join(f"0.{i:06d} 1 2 1\n" for i in range(5000)) + "0.5 1 2 x\n")
    with pytest.raises(InputError, match="line 5001: polarity"):
        list(iter_ecd_events(f, block_bytes=1000))


@pytest.mark.parametrize(
    "name, text, message",
    [
        ("events.txt", "", "contains no events"),
        ("calib.txt", "1 2 3\n", "expected 9 values"),
        ("calib.txt", "1 2 3 4 5 6 7 8 x\n", "not a number"),
        ("calib.txt", "1 2 3 4 5 6 7 8 nan\n", "NaN or infinite"),
        ("imu.txt", "0.0 1 2 3 4 5\n", "line 1: expected 7 values, got 6"),
        ("imu.txt", "0.0 1 2 3 4 5 6\n0.0 1 2 3 4 5 6\n", "line 2: timestamp 0.0 does not increase"),
        ("imu.txt", "0.0 1 2 nan 4 5 6\n", "line 1: NaN or infinite value"),
        ("imu.txt", "", "contains no IMU samples"),
        ("groundtruth.txt", "# t x y z qx qy qz qw\n0.0 1 2 3 0 0 0 0\n", "line 2: quaternion has zero length"),
        ("groundtruth.txt", "0.0 1 2 3 0 0 0\n", "line 1: expected 8 values"),
        # The checks after parsing named the folder and a 0-based sample: "ecd: IMU sample 0: acceleration ...".
        ("imu.txt", "0.0 1 2 3 4 5 6\n\n0.001 9000 2 3 4 5 6\n", "imu.txt: line 3: acceleration 9e\\+03 m/s\\^2 is beyond"),
        ("groundtruth.txt", "0.0 1 2 3 0 0 0 1\n0.001 1e9 2 3 0 0 0 1\n", "groundtruth.txt: line 2: position .* is beyond"),
        ("evpose.json", '{"metadata": 5}', "evpose.json: metadata: expected a JSON object, got int"),
    ],
)
def test_bad_side_files_name_file_record_and_problem(tmp_path, name, text, message):
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("0.1 1 2 1\n")
    (d / name).write_text(text)
    with pytest.raises(InputError, match=message) as err:
        read_ecd_folder(d, 240, 180)
    assert str(err.value).startswith(str(d / name))


@pytest.mark.parametrize("name", ["imu.txt", "groundtruth.txt", "calib.txt", "evpose.json"])
def test_a_folder_in_place_of_a_side_file_is_named_not_skipped(tmp_path, name):
    # It was skipped: a recording without its IMU, ground truth or calibration, and exit 0.
    d = tmp_path / "ecd"
    d.mkdir()
    (d / "events.txt").write_text("0.1 1 2 1\n")
    (d / name).mkdir()
    with pytest.raises(InputError, match=f"{name}: is a folder, not a file"):
        read_ecd_folder(d, 240, 180)


def test_missing_folder_and_missing_events_file(tmp_path):
    with pytest.raises(InputError, match="no such folder"):
        read_ecd_folder(tmp_path / "nope")
    (tmp_path / "x").mkdir()
    with pytest.raises(InputError, match="events.txt: no such file"):
        read_ecd_folder(tmp_path / "x")


def test_write_is_atomic_and_never_overwrites_the_input_folder(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    rec = read_ecd_folder(tmp_path / "seq")
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        write_ecd_folder(tmp_path / "seq", rec)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seq"]


def test_write_replaces_an_earlier_ecd_folder_but_never_a_folder_with_other_files(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    write_ecd_folder(tmp_path / "seq", recording)  # a rerun replaces its own output
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "precious.bag").write_text("keep")
    with pytest.raises(InputError, match=r"data: refusing to replace a folder that is not an ECD recording \(it holds 'precious.bag'\)"):
        write_ecd_folder(tmp_path / "data", recording)
    assert (tmp_path / "data" / "precious.bag").read_text() == "keep"


def test_sensor_size_flags_that_contradict_the_sidecar_calibration_name_the_sidecar_and_the_flags(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)  # 240x180
    with pytest.raises(InputError, match=r"seq/evpose.json: --width/--height 100x80 contradict the 240x180 sensor stated by its calibration"):
        read_ecd_folder(tmp_path / "seq", 100, 80)


def test_sidecar_metadata_size_that_is_not_a_size_names_the_sidecar(tmp_path, recording):
    import dataclasses
    import json

    write_ecd_folder(tmp_path / "seq", dataclasses.replace(recording, calibration=None, metadata={"width": 240, "height": 180}))
    side = tmp_path / "seq" / "evpose.json"
    doc = json.loads(side.read_text())
    doc["metadata"]["width"] = "big"  # int("big") was a ValueError traceback
    side.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=r"seq/evpose.json: metadata width/height 'big' x 180 is not a sensor size"):
        read_ecd_folder(tmp_path / "seq")


@pytest.mark.parametrize(
    "text, message",
    [
        ("1 2 3\n", "expected 9 values"),
        ("200 200 x 130 0 0 0 0 0\n", "not a number"),
        ("nan 200 170 130\n", "NaN or infinite"),
        ("", "expected 9 values"),
    ],
)
def test_a_damaged_calib_txt_beside_the_sidecar_is_refused_not_ignored(tmp_path, recording, text, message):
    write_ecd_folder(tmp_path / "seq", recording)
    (tmp_path / "seq" / "calib.txt").write_text(text)
    with pytest.raises(InputError, match=message) as err:
        read_ecd_folder(tmp_path / "seq")
    assert str(err.value).startswith(str(tmp_path / "seq" / "calib.txt"))


def test_a_calib_txt_that_contradicts_the_sidecar_names_the_value_and_the_file_used(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    calib = tmp_path / "seq" / "calib.txt"
    vals = calib.read_text().split()
    calib.write_text(" ".join([vals[0], vals[1], "12.5", *vals[3:]]) + "\n")
    with pytest.raises(InputError, match=r"calib.txt: cx 12.5 contradicts the calibration in evpose.json \(cx .*\), which is the one used"):
        read_ecd_folder(tmp_path / "seq")


def test_a_calib_txt_that_agrees_with_the_sidecar_is_accepted_however_written(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    calib = tmp_path / "seq" / "calib.txt"
    vals = [float(v) for v in calib.read_text().split()]
    calib.write_text("\t".join(f"{v:.6e}" for v in vals) + "\n\n")  # other spacing and notation, the same numbers
    assert read_ecd_folder(tmp_path / "seq").calibration.to_dict() == recording.calibration.to_dict()
    calib.write_text(" ".join(str(v) for v in vals[:4]) + "\n")  # no distortion: the sidecar's lens has some
    with pytest.raises(InputError, match="calib.txt: k1 0.0 contradicts"):
        read_ecd_folder(tmp_path / "seq")
    calib.unlink()  # the sidecar alone
    assert read_ecd_folder(tmp_path / "seq").calibration.to_dict() == recording.calibration.to_dict()


def test_a_calib_txt_rounded_for_print_agrees_with_the_sidecar_but_zero_distortion_is_exact(tmp_path, recording):
    write_ecd_folder(tmp_path / "seq", recording)
    calib = tmp_path / "seq" / "calib.txt"
    cal = recording.calibration
    rounded = [f"{v:.2f}" for v in (cal.fx, cal.fy, cal.cx, cal.cy)] + [f"{v:.3g}" for v in cal.dist]
    calib.write_text(" ".join(rounded) + "\n")
    assert read_ecd_folder(tmp_path / "seq").calibration.to_dict() == cal.to_dict()  # the sidecar's exact values
    calib.write_text(" ".join(rounded[:4] + ["0"] * 5) + "\n")  # "no distortion", beside a sidecar with some
    with pytest.raises(InputError, match="k1 0.0 contradicts"):
        read_ecd_folder(tmp_path / "seq")
