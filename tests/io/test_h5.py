"""evpose HDF5: round trip, windowed reads through the time index, streaming writer, bad files."""

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from io_factory import assert_same_recording, make_recording
from evpose.core.events import EventArray
from evpose.errors import InputError
from evpose.io.h5 import Compression, H5RecordingReader, H5RecordingWriter, H5WriteConfig, read_recording_h5, write_recording_h5


@pytest.mark.parametrize("compression", list(Compression))
def test_round_trip_is_exact_for_every_compression(tmp_path, recording, compression):
    path = tmp_path / "r.h5"
    write_recording_h5(path, recording, H5WriteConfig(compression=compression, chunk_events=4096))
    assert_same_recording(recording, read_recording_h5(path))


def test_recording_without_calibration_keeps_metadata_size(tmp_path):
    rec = make_recording(with_calibration=False)
    write_recording_h5(tmp_path / "r.h5", rec)
    back = read_recording_h5(tmp_path / "r.h5")
    assert back.calibration is None and back.sensor_size == (240, 180)
    assert_same_recording(rec, back)


_REC = make_recording(n=5000, seed=3, duration_us=40_000)


@pytest.fixture(scope="module")
def h5file(tmp_path_factory):
    path = tmp_path_factory.mktemp("h5") / "w.h5"
    write_recording_h5(path, _REC, H5WriteConfig(chunk_events=512))
    return path


@settings(max_examples=60, deadline=None)
@given(st.integers(_REC.t_start_us - 3000, _REC.t_end_us + 3000), st.integers(0, 45_000))
def test_windowed_read_equals_slicing_the_full_arrays(h5file, t0, length):
    t1 = t0 + length
    with H5RecordingReader(h5file) as r:
        got = r.read_events(t0, t1)
    want = _REC.events.time_window(t0, t1)
    for c in "txyp":
        np.testing.assert_array_equal(getattr(got, c), getattr(want, c))


def test_windowed_recording_windows_imu_on_its_own_clock_and_ground_truth(h5file):
    t0, t1 = _REC.t_start_us + 10_000, _REC.t_start_us + 20_000
    rec = read_recording_h5(h5file, t0, t1)
    off = _REC.calibration.time_offset_us
    np.testing.assert_array_equal(rec.imu.t, _REC.imu.time_window(t0 + off, t1 + off).t)
    np.testing.assert_array_equal(rec.ground_truth.t, _REC.ground_truth.time_window(t0, t1).t)


def test_streaming_writer_equals_one_shot_write(tmp_path, recording):
    with H5RecordingWriter(tmp_path / "s.h5", config=H5WriteConfig(chunk_events=1000)) as w:
        w.set_metadata(recording.metadata)
        w.set_calibration(recording.calibration)
        w.set_imu(recording.imu)
        w.set_ground_truth(recording.ground_truth)
        for i0 in range(0, len(recording.events), 777):
            w.append_events(recording.events[i0 : i0 + 777])
    assert_same_recording(recording, read_recording_h5(tmp_path / "s.h5"))
    with h5py.File(tmp_path / "s.h5") as f:
        idx = f["events/ms_to_idx"][()]
        origin = f["events/ms_to_idx"].attrs["t_origin_us"]
    t = recording.events.t
    np.testing.assert_array_equal(idx[:-1], np.searchsorted(t, origin + 1000 * np.arange(idx.size - 1)))
    assert idx[-1] == t.size


def test_writer_rejects_batches_out_of_order_and_leaves_no_file(tmp_path):
    ev = EventArray.from_arrays([10, 20], [0, 0], [0, 0], [1, 1])
    with pytest.raises(InputError, match="event 2: timestamp 5 us is earlier than the previous 20 us"):
        with H5RecordingWriter(tmp_path / "o.h5") as w:
            w.append_events(ev)
            w.append_events(EventArray.from_arrays([5], [0], [0], [1]))
    assert list(tmp_path.iterdir()) == []


def test_iter_chunks_covers_all_events(h5file):
    with H5RecordingReader(h5file) as r:
        parts = list(r.iter_chunks(1234))
    np.testing.assert_array_equal(EventArray.concatenate(parts).t, _REC.events.t)


def test_empty_event_stream_round_trips(tmp_path):
    rec = make_recording(n=0)
    write_recording_h5(tmp_path / "e.h5", rec)
    back = read_recording_h5(tmp_path / "e.h5", 0, 10)
    assert len(back.events) == 0


def test_metadata_must_be_json_serialisable(tmp_path, recording):
    recording.metadata = {"bad": object()}
    with pytest.raises(InputError, match="JSON"):
        write_recording_h5(tmp_path / "m.h5", recording)
    assert list(tmp_path.iterdir()) == []


def test_reading_a_file_that_is_not_ours_names_the_problem(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        H5RecordingReader(tmp_path / "missing.h5")
    (tmp_path / "text.h5").write_text("hello")
    with pytest.raises(InputError, match="not an HDF5 file"):
        H5RecordingReader(tmp_path / "text.h5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(InputError, match="not an evpose recording"):
        H5RecordingReader(tmp_path / "other.h5")


def test_writing_never_overwrites_the_input(tmp_path, recording):
    path = tmp_path / "r.h5"
    write_recording_h5(path, recording)
    rec = read_recording_h5(path)
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        write_recording_h5(path, rec)


def test_absurd_time_span_is_an_input_error_not_a_huge_index(tmp_path):
    ev = EventArray.from_arrays([0, 1, 10**15], [0, 0, 0], [0, 0, 0], [1, 1, 1])
    with pytest.raises(InputError, match="src.txt: event 2: events span .* hours"):
        with H5RecordingWriter(tmp_path / "o.h5") as w:
            w.append_events(ev, source="src.txt")
    assert list(tmp_path.iterdir()) == []
