"""evpose HDF5 reader: a file that breaks the schema (docs/recording_h5.md) is a one-line InputError naming the dataset,
never a silent cast, a traceback deep inside a command, or a huge allocation."""

import json
import os

import h5py
import numpy as np
import pytest

from io_factory import make_recording
from evpose.errors import InputError
from evpose.io.h5 import H5RecordingReader, H5WriteConfig, read_recording_h5, write_recording_h5
from evpose.io.open import open_recording, open_stream

_REC = make_recording(n=4000, seed=5, duration_us=50_000)


@pytest.fixture
def h5copy(tmp_path):
    path = tmp_path / "r.h5"
    write_recording_h5(path, _REC, H5WriteConfig(chunk_events=1024))
    return path


def _replace(f, name, data):
    del f[name]
    f.create_dataset(name, data=data)


def _edit(path, fn):
    with h5py.File(path, "r+") as f:
        fn(f)


def _error(path) -> str:
    with pytest.raises(InputError) as info:
        read_recording_h5(path)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg
    return msg


def test_float_event_times_are_refused_not_cast(h5copy):
    # A NaN time would be cast to -2**63 and the recording would "track" fine.
    def fn(f):
        t = f["events/t"][()].astype(np.float64)
        t[10] = np.nan
        _replace(f, "events/t", t)

    _edit(h5copy, fn)
    assert "dataset 'events/t' is dtype float64, expected an integer dtype" in _error(h5copy)


def test_string_pixel_column_is_refused(h5copy):
    _edit(h5copy, lambda f: _replace(f, "events/x", np.array([b"a"] * f["events/x"].shape[0])))
    assert "dataset 'events/x' is dtype |S1" in _error(h5copy)



@pytest.mark.parametrize("column, dtype, value, message", [
    ("x", np.int32, -3, "x=-3 does not fit the schema's uint16"),
    ("y", np.int64, 70_000, "y=70000 does not fit the schema's uint16"),
    ("p", np.int16, 257, "p=257 does not fit the schema's int8"),
])
def test_event_column_of_another_integer_dtype_is_checked_before_the_cast(h5copy, column, dtype, value, message):
    # An int32 x of -3 passed the bounds check (x >= width) and the kernels indexed pixel -3; p=257 became +1.
    def fn(f):
        col = f[f"events/{column}"][()].astype(dtype)
        col[7] = value
        _replace(f, f"events/{column}", col)

    _edit(h5copy, fn)
    assert f"event 7: {message}" in _error(h5copy)
    with H5RecordingReader(h5copy) as r:
        with pytest.raises(InputError, match="event 7"):
            r.read_events(None, None)


def test_event_column_of_another_integer_dtype_that_fits_reads_in_the_schema_dtypes(h5copy):
    _edit(h5copy, lambda f: _replace(f, "events/x", f["events/x"][()].astype(np.int32)))
    rec = read_recording_h5(h5copy)
    assert rec.events.x.dtype == np.uint16 and np.array_equal(rec.events.x, _REC.events.x)


def test_two_dimensional_event_column_names_its_shape(h5copy):
    _edit(h5copy, lambda f: _replace(f, "events/y", np.stack([f["events/y"][()]] * 2, axis=1)))
    msg = _error(h5copy)
    assert "dataset 'events/y' has shape" in msg and f"expected ({len(_REC.events)},)" in msg


@pytest.mark.parametrize("name, cols", [("imu/acc", 3), ("ground_truth/quat_xyzw", 4)])
def test_small_stream_with_wrong_columns_names_the_dataset(h5copy, name, cols):
    _edit(h5copy, lambda f: _replace(f, name, f[name][()][:, :2]))
    assert f"dataset {name!r} has shape" in _error(h5copy) and f"{cols})" in _error(h5copy)


def test_far_future_last_timestamp_is_refused_at_open_not_allocated(h5copy):
    # The index spans the real events; a damaged last time of 2**62 us made `track` allocate gigabytes of time bins.
    def fn(f):
        t = f["events/t"][()]
        t[-1] = 2**62
        f["events/t"][...] = t

    _edit(h5copy, fn)
    msg = _error(h5copy)
    assert f"event {len(_REC.events) - 1}: events/ms_to_idx" in msg and "does not span the events" in msg


def test_zero_length_ground_truth_quaternion_names_the_pose(h5copy):
    def fn(f):
        q = f["ground_truth/quat_xyzw"][()]
        q[2] = 0.0
        f["ground_truth/quat_xyzw"][...] = q

    _edit(h5copy, fn)
    assert "ground-truth pose 2: quaternion has zero length" in _error(h5copy)


@pytest.mark.parametrize("attr, value, message", [
    ("evpose_format_version", "one", "attribute 'evpose_format_version' is 'one', not an integer"),
    ("metadata", "[1, 2]", "attribute 'metadata' is a JSON list, expected an object"),
    ("calibration", "3", "attribute 'calibration' is a JSON int, expected an object"),
])
def test_malformed_root_attributes_are_named(h5copy, attr, value, message):
    _edit(h5copy, lambda f: f.attrs.__setitem__(attr, value))
    assert message in _error(h5copy)


def test_a_chunk_that_fails_to_decompress_is_a_damaged_file_error(tmp_path):
    path = tmp_path / "r.h5"
    write_recording_h5(path, make_recording(n=200_000, seed=1), H5WriteConfig(chunk_events=8192))
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 65536] = np.random.default_rng(0).integers(0, 256, 65536, dtype=np.uint8).tobytes()
    path.write_bytes(bytes(data))
    with pytest.raises(InputError) as info:
        open_recording(path)
    assert "the file is damaged" in str(info.value) and "\n" not in str(info.value)


def test_negative_event_times_are_refused_by_every_reader(tmp_path):
    rec = make_recording(n=1000, seed=2, t0=0, duration_us=20_000)
    rec.events.t[:] -= 5_000_000
    path = tmp_path / "neg.h5"
    write_recording_h5(path, rec)
    with pytest.raises(InputError, match="event 0: timestamp -4.* us is negative"):
        open_recording(path)
    with pytest.raises(InputError, match="is negative"):
        list(open_stream(path).batches(None))
    from evpose.io.summary import summarize_recording  # `evpose info` reads HDF5 through its own path

    with pytest.raises(InputError, match="event 0: timestamp -4.* us is negative"):
        summarize_recording(path)


def test_nan_imu_sample_is_refused_when_streaming(h5copy):
    # `convert` streams: without this check it copied the NaN into a "valid" new file.
    def fn(f):
        a = f["imu/acc"][()]
        a[4, 1] = np.nan
        f["imu/acc"][...] = a

    _edit(h5copy, fn)
    with pytest.raises(InputError, match="IMU sample 4: NaN"):
        open_stream(h5copy)


@pytest.mark.parametrize("kw, missing", [
    ({"shape": (10**13,), "chunks": (1 << 16,)}, "has 0 of its 152587891 chunks written"),
    ({"shape": (10**6,)}, "stores 0 of its 8000000 bytes"),
])
def test_a_dataset_declaring_more_values_than_the_file_stores_is_named_before_reading_it(tmp_path, kw, missing):
    # 10**13 IMU samples declared in a 1.5 MB file ended in numpy's "Unable to allocate 72.8 TiB" traceback; a smaller
    # declaration could fill the memory with zeros.
    path = tmp_path / "r.h5"
    write_recording_h5(path, make_recording(n=100))
    with h5py.File(path, "r+") as f:
        del f["imu"]
        f.create_dataset("imu/t", dtype="i8", **kw)
    with pytest.raises(InputError, match=f"r.h5: dataset 'imu/t' {missing}: the file is damaged or was never finished"):
        read_recording_h5(path)
