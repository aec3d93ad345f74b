"""Bad recordings and maps opened from the viewer in a real headless Chromium: a one-line error naming the file, the
record and the problem, no traceback, and the viewer goes on (the good recording still opens and plays)."""

import dataclasses
import shutil

import numpy as np
import pytest

from app.player import PlayerConfig
from app.tracker_engine import TrackerEngine
from browser_session import choose, running_viewer, wait_for

pytestmark = pytest.mark.browser

BAD_RECORDINGS = {  # file -> what the error says of it
    "squares_trunc.h5": "squares_trunc.h5: not an HDF5 file",
    "squares_unsorted.h5": "squares_unsorted.h5: event 101: timestamp",
    "squares_nan_imu.h5": "squares_nan_imu.h5: IMU sample 5: NaN or infinite value",
    "squares_no_events.h5": "squares_no_events.h5: contains no events",
}
BAD_MAPS = {
    "map_nan_normals.ply": "map_nan_normals.ply: point 7: NaN or infinite edge normal",
    "map_trunc.ply": "map_trunc.ply: file is truncated",
}


def _edit_h5(src, dst, fn):
    import h5py
    import hdf5plugin  # noqa: F401  (the events' compression filter)

    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as f:
        fn(f)


def _set(name, index, value):
    def fn(f):
        a = f[name][()]
        a[index] = value
        f[name][...] = a
    return fn


def _no_events(f):
    for c in ("t", "x", "y", "p", "ms_to_idx"):
        attrs, dtype = dict(f[f"events/{c}"].attrs), f[f"events/{c}"].dtype
        del f[f"events/{c}"]
        f[f"events/{c}"] = np.zeros(1 if c == "ms_to_idx" else 0, dtype)
        f[f"events/{c}"].attrs.update(attrs)
    f["events"].attrs["count"] = 0


def write_bad_data_root(root, squares_scene):
    """The squares recording and its map, next to a copy of each broken in one way."""
    from evpose.io.h5 import write_recording_h5
    from evpose.io.map_ply import write_contour_map

    rec, cmap = squares_scene
    good = root / "squares.h5"
    write_recording_h5(good, rec)
    write_contour_map(root / "squares_map.ply", cmap)
    raw = good.read_bytes()
    (root / "squares_trunc.h5").write_bytes(raw[: len(raw) // 2])
    t = rec.events.t
    _edit_h5(good, root / "squares_unsorted.h5", _set("events/t", 101, t[100] - 10))
    _edit_h5(good, root / "squares_nan_imu.h5", _set("imu/acc", (5, 0), np.nan))
    _edit_h5(good, root / "squares_no_events.h5", _no_events)
    _edit_h5(good, root / "squares_no_calib.h5", lambda f: f.attrs.__delitem__("calibration"))
    normals = cmap.edge_normal.copy()
    normals[7, 0] = np.nan
    write_contour_map(root / "map_nan_normals.ply", dataclasses.replace(cmap, edge_normal=normals))
    ply = (root / "squares_map.ply").read_bytes()
    (root / "map_trunc.ply").write_bytes(ply[: len(ply) // 2])
    return root


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, squares_scene):
    root = write_bad_data_root(tmp_path_factory.mktemp("data"), squares_scene)
    with running_viewer(tmp_path_factory, root, warm_up=True, player=PlayerConfig(prefetch=False)) as app:
        yield app


def _option(viewer, dropdown, file_name):
    return next(o for o in dropdown.options if o.split(" ")[0].endswith("/" + file_name))


def _page_text(page):
    return page.locator("body").inner_text()


def test_bad_recordings_and_maps_give_a_one_line_error_and_the_good_recording_still_plays(page, viewer, capfd):
    wait_for(lambda: viewer.last_frame is not None and viewer.recording is not None, timeout=90, what="squares opened")
    # What the headers tell is in the list before anything is opened.
    assert _option(viewer, viewer.rec_dropdown, "squares_no_events.h5").endswith("(unreadable: contains no events)")
    for name, said in BAD_RECORDINGS.items():
        choose(page, "recording", _option(viewer, viewer.rec_dropdown, name))
        wait_for(lambda: said in _page_text(page), timeout=20, what=f"{name} refused", detail=lambda: viewer.rec_info.content)
        assert f"**Cannot open:** {viewer.roots.roots[0]}/{said}" in viewer.rec_info.content
        assert viewer.rec_dropdown.value.endswith("/squares.h5")  # still the recording shown
    # Without calibration the events are shown, and the status line says why nothing is tracked.
    choose(page, "recording", _option(viewer, viewer.rec_dropdown, "squares_no_calib.h5"))
    wait_for(lambda: "squares_no_calib.h5: the recording has no camera calibration" in viewer.status.content, timeout=30,
             what="no-calibration reason in the status line", detail=lambda: viewer.status.content)
    page.get_by_text("the recording has no camera calibration").first.wait_for(timeout=10_000)
    choose(page, "recording", _option(viewer, viewer.rec_dropdown, "squares.h5"))
    wait_for(lambda: isinstance(viewer.player.engine, TrackerEngine), timeout=30, what="squares back")
    for name, said in BAD_MAPS.items():
        choose(page, "map", _option(viewer, viewer.map_dropdown, name))
        wait_for(lambda: said in _page_text(page), timeout=20, what=f"{name} refused", detail=lambda: viewer.rec_info.content)
        assert viewer.map_dropdown.value.endswith("/squares_map.ply")
    viewer.player.wait_idle()
    start = viewer.last_frame.index
    viewer.player.set_speed(0.2)
    page.get_by_role("button", name="play / pause (space)").click()
    wait_for(lambda: viewer.last_frame.index >= start + 5, what="the good recording plays")
    page.get_by_role("button", name="play / pause (space)").click()
    assert isinstance(viewer.player.engine, TrackerEngine) and viewer.last_frame.status != "events only"
    assert "Traceback" not in _page_text(page)
    assert "Traceback" not in capfd.readouterr().err


def test_the_warm_up_reports_each_bad_recording_on_one_line_naming_the_record_and_goes_on(page, viewer):
    root = viewer.roots.roots[0].name
    unreadable = ("squares_trunc.h5", "squares_no_events.h5")  # marked by the scan, never queued
    bad = [f"{root}/{n}" for n in [*BAD_RECORDINGS, "squares_no_calib.h5"] if n not in unreadable]
    settled = lambda: all(viewer.warm_up.states.get(b, "").startswith("failed") for b in bad)
    wait_for(settled, timeout=90, what="the warm-up went through the bad recordings", detail=lambda: viewer.warm_up.states)
    states = viewer.warm_up.states
    assert states[f"{root}/squares_nan_imu.h5"] == "failed: IMU sample 5: NaN or infinite value"
    assert states[f"{root}/squares_unsorted.h5"].startswith("failed: event 101: timestamp")
    assert states[f"{root}/squares_no_calib.h5"] == ("failed: tracking cannot start: the recording has no camera "
                                                     "calibration; tracking needs intrinsics")  # the label, not the path
    assert all(f"{root}/{n}" not in states for n in unreadable)
    assert all("\n" not in v for v in states.values())
    page.get_by_text("failed: IMU sample 5: NaN or infinite value").first.wait_for(timeout=10_000)
