"""Recordings browser: listing, unreadable files with reasons, and the data-root restriction."""

import os

import pytest

from app.browser import DataRoots, EntryKind, guess_map_for, load_recording
from evpose.core.contour_map import ContourMap
from evpose.errors import InputError
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import write_contour_map


@pytest.fixture
def data_dir(tmp_path, bar_recording):
    root = tmp_path / "data"
    (root / "sub").mkdir(parents=True)
    write_recording_h5(root / "squares_run1.h5", bar_recording)
    (root / "sub" / "broken.h5").write_bytes(b"not hdf5 at all")
    write_contour_map(root / "squares_map.ply", ContourMap.from_points([[0, 0, 0], [1, 0, 0], [0, 1, 0]]))
    (root / "bad_map.ply").write_text("hello")
    return root


def test_scan_lists_recordings_and_maps_and_explains_unreadable_files(data_dir):
    entries = DataRoots([data_dir]).scan()
    by_name = {e.path.name: e for e in entries}
    assert by_name["squares_run1.h5"].kind == EntryKind.RECORDING and by_name["squares_run1.h5"].error is None
    assert by_name["broken.h5"].error == "not an HDF5 file"
    assert "unreadable" in by_name["broken.h5"].display
    assert by_name["squares_map.ply"].kind == EntryKind.MAP and by_name["squares_map.ply"].error is None
    assert "PLY" in by_name["bad_map.ply"].error


def test_paths_outside_the_data_roots_are_refused(data_dir, tmp_path):
    roots = DataRoots([data_dir])
    assert roots.check(data_dir / "squares_run1.h5") == (data_dir / "squares_run1.h5").resolve()
    assert roots.check("squares_run1.h5") == (data_dir / "squares_run1.h5").resolve()
    secret = tmp_path / "secret.h5"
    secret.write_bytes(b"x")
    for bad in (secret, data_dir / ".." / "secret.h5", "../secret.h5", "/etc/passwd"):
        with pytest.raises(InputError, match="outside the data directories"):
            roots.check(bad)


def test_a_symlink_leading_out_of_the_roots_is_listed_but_refused(data_dir, tmp_path):
    outside = tmp_path / "outside.h5"
    outside.write_bytes(b"x")
    os.symlink(outside, data_dir / "link.h5")
    entry = {e.path.name: e for e in DataRoots([data_dir]).scan()}["link.h5"]
    assert entry.error and "outside" in entry.error
    with pytest.raises(InputError):
        DataRoots([data_dir]).check(data_dir / "link.h5")


def test_map_is_guessed_from_the_recording_name_and_recordings_load(data_dir):
    entries = DataRoots([data_dir]).scan()
    rec = next(e for e in entries if e.path.name == "squares_run1.h5")
    maps = [e for e in entries if e.kind == EntryKind.MAP]
    assert guess_map_for(rec, maps).path.name == "squares_map.ply"
    assert len(load_recording(rec.path).events) > 0


def test_recordings_refused_on_opening_are_marked_at_scan_time_from_their_headers(data_dir, bar_recording):
    import dataclasses

    from evpose.core.events import EventArray
    from evpose.io.ecd import write_ecd_folder

    write_recording_h5(data_dir / "no_events.h5", dataclasses.replace(bar_recording, events=EventArray.empty()))
    write_ecd_folder(data_dir / "ecd_good", bar_recording)
    bad = {"ecd_empty": "", "ecd_comments": "# t x y p\n\n", "ecd_words": "# t x y p\ntime x y polarity\n0.1 2 3 1\n",
           "ecd_three": "0.1 2 3\n"}
    for name, text in bad.items():
        (data_dir / name).mkdir()
        (data_dir / name / "events.txt").write_text(text)
    (data_dir / "ecd_calib").mkdir()
    (data_dir / "ecd_calib" / "events.txt").write_text("0.1 2 3 1\n")
    (data_dir / "ecd_calib" / "calib.txt").write_text("200 200 nan 100\n")
    (data_dir / "ecd_link").mkdir()
    os.symlink(data_dir / "gone.txt", data_dir / "ecd_link" / "events.txt")
    errors = {e.path.name: e.error for e in DataRoots([data_dir]).scan() if e.kind == EntryKind.RECORDING}
    assert errors["no_events.h5"] == "contains no events"
    assert errors["ecd_good"] is None and errors["squares_run1.h5"] is None
    assert errors["ecd_empty"] == errors["ecd_comments"] == "events.txt: contains no events"
    assert errors["ecd_words"] == "events.txt: line 2: expected 4 numbers 't x y p', got 'time x y polarity'"
    assert errors["ecd_three"] == "events.txt: line 1: expected 4 numbers 't x y p', got '0.1 2 3'"
    assert errors["ecd_calib"] == "calib.txt: NaN or infinite calibration value"
    assert errors["ecd_link"] == "events.txt: no such file"
    for name in ("no_events.h5", "ecd_empty", "ecd_three"):  # what opening says too: the scan does not invent problems
        with pytest.raises(InputError):
            load_recording(data_dir / name)


def test_event_h5_files_of_other_layouts_are_listed_as_readable(data_dir, bar_recording):
    from evpose.io.event_h5 import write_event_h5

    write_event_h5(data_dir / "events_left.h5", bar_recording.events)
    entry = {e.path.name: e for e in DataRoots([data_dir]).scan()}["events_left.h5"]
    assert entry.kind == EntryKind.RECORDING and entry.error is None
