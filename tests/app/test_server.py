"""The viewer without a browser: data handling, bad input, the port check, exports."""

import socket
import threading
import time

import pytest

from app.engine import EventsOnlyEngine
from app.tracker_engine import TrackerEngine
from app.player import PlayerConfig
from app.server import NO_MAP, AppConfig, ViewerApp, check_port_free
from evpose.cli.main import run
from evpose.errors import InputError
from evpose.io.h5 import write_recording_h5
from evpose.io.map_ply import write_contour_map


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def data_root(tmp_path_factory, squares_scene):
    from app_scenes import write_data_root

    return write_data_root(tmp_path_factory.mktemp("data"), squares_scene)


@pytest.fixture(scope="module")
def viewer(data_root, tmp_path_factory):
    app = ViewerApp(AppConfig(data=[data_root], port=free_port(), export_dir=tmp_path_factory.mktemp("exports"),
                              player=PlayerConfig(prefetch=False)))
    yield app
    app.stop()


def test_port_in_use_gives_one_clear_line(capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(InputError, match=f"cannot serve on 127.0.0.1:{port}"):
            check_port_free("127.0.0.1", port)
        assert run(["app", "--port", str(port), "--data", "."]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "choose another --port" in err[0]


def test_corrupt_file_is_listed_with_its_reason_and_cannot_crash_the_server(viewer):
    assert "corrupt.h5" in viewer.rec_info.content and "Unreadable" in viewer.rec_info.content
    bad = next(e for e in viewer.entries if e.path.name == "corrupt.h5")
    viewer.rec_dropdown.value = bad.display  # as the browser's dropdown does when the user picks it
    assert viewer.select(bad.display) is False
    assert "Cannot open" in viewer.rec_info.content
    assert viewer.player is not None and viewer.player._thread.is_alive()
    # The dropdown names the recording still shown, not the refused file.
    assert viewer.rec_dropdown.value == viewer._open_displays[0] != bad.display


def test_the_playback_controls_come_before_the_list_of_prepared_recordings(viewer):
    # The list grows with the recordings found; above the controls it pushed them off the screen.
    assert viewer.rec_info.order < viewer.play_button.order < viewer.status.order < viewer.warm_info.order


def test_the_playback_controls_say_on_hover_what_they_do_and_their_keys(viewer):
    # They had no hover text: their keys were in the README and the command palette only (session 27 audit).
    hints = {"play": viewer.play_button.hint, "step": viewer.step_buttons.hint, "time": viewer.time_slider.hint,
             "speed": viewer.speed_slider.hint, "loop": viewer.loop_box.hint}
    assert all(hints.values()), hints
    assert "Space" in hints["play"] and "arrow keys" in hints["step"] and "Home" in hints["time"]
    assert "up / down" in hints["speed"]


def test_the_status_says_a_recording_is_opening_until_its_first_step_is_drawn(viewer):
    gate = threading.Event()
    viewer.player.call(lambda engine: gate.wait(20))  # the worker busy, as with a first step loading its kernels
    try:
        assert viewer.select(next(e.display for e in viewer.entries if e.path.name == "bar.h5"), NO_MAP)
        assert "opening" in viewer.status.content and "bar.h5" in viewer.status.content
    finally:
        gate.set()
    viewer.player.wait_idle()
    assert "step 0" in viewer.status.content and "opening" not in viewer.status.content


def test_a_first_step_that_fails_is_said_in_the_status_line(viewer, monkeypatch):
    def failing(self):
        raise RuntimeError("boom")

    monkeypatch.setattr(EventsOnlyEngine, "step", failing)
    assert viewer.select(next(e.display for e in viewer.entries if e.path.name == "bar.h5"), NO_MAP)
    viewer.player.wait_idle()
    assert "could not show its first step" in viewer.status.content and "boom" in viewer.status.content
    monkeypatch.undo()
    viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.wait_idle()
    assert "step 0" in viewer.status.content


def test_a_step_that_fails_later_is_said_in_the_status_line_after_the_notification_closes(viewer, monkeypatch):
    assert viewer.select(next(e.display for e in viewer.entries if e.path.name == "bar.h5"), NO_MAP)
    viewer.player.wait_idle()

    def failing(self, index):
        raise RuntimeError("boom")

    monkeypatch.setattr(EventsOnlyEngine, "seek_step", failing)
    for _ in range(2):  # the second failure replaces the first line, it does not pile up
        viewer.player.step_forward()
        viewer.player.wait_idle()
    assert viewer.status.content.count("**error:** step failed: boom") == 1 and "step 0" in viewer.status.content
    monkeypatch.undo()
    viewer.player.step_forward()
    viewer.player.wait_idle()
    assert "error" not in viewer.status.content and "step 1" in viewer.status.content


def test_a_layout_that_shows_the_teaching_panel_draws_the_shown_step_into_it(viewer):
    assert viewer.apply_layout_name("debug") and not viewer.panels["teaching"].visible
    viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.step_forward()
    viewer.player.wait_idle()
    blank = viewer.teaching_image.image.copy()
    assert viewer.apply_layout_name("teaching")
    viewer.player.wait_idle()
    assert viewer.teaching_image.image.shape != blank.shape  # the live image, not the placeholder
    assert "Press play" not in viewer.teaching_text.content
    viewer.apply_layout_name("debug")


def test_the_teaching_image_colours_the_map_points_as_its_stage_explains_them(viewer):
    # The polarity stage showed the points by residual (the Images panel's choice) while its text spoke of red and
    # blue; the registration stage said "green = on an edge" with the points coloured by weight.
    from app.panels import OverlayColour, tdf_image

    viewer.stage_dropdown.value = "fusion"
    assert viewer.apply_layout_name("teaching") and viewer.stage.value == "events"  # where a lesson starts
    viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.seek(viewer.recording.t_start_us + 100_000)
    viewer.player.wait_idle()
    try:
        viewer._set_overlay(OverlayColour.WEIGHT.value)
        viewer.stage_dropdown.value = "TDF"
        viewer.step_stage(1)  # the lesson's next stage
        viewer.player.wait_idle()
        assert viewer.stage.value == "polarity prediction" and viewer.teaching_image.label.endswith("coloured by predicted polarity")
        frame = viewer.last_frame
        assert frame.predicted_polarity is not None and len(frame.projected_uv)
        assert (viewer.teaching_image.image == tdf_image(frame, OverlayColour.POLARITY)).all()
        viewer.step_stage(1)
        viewer.player.wait_idle()
        assert viewer.stage.value == "registration"
        assert (viewer.teaching_image.image == tdf_image(frame, OverlayColour.RESIDUAL)).all()
        # The fusion stage names the 3D elements the teaching layout hides, and drops them once ticked.
        viewer.step_stage(1)
        viewer.player.wait_idle()
        assert "the raw registrations (purple)" in viewer.teaching_text.content
        viewer.toggle_boxes["registration"].value = True
        viewer.player.wait_idle()
        assert "the raw registrations (purple)" not in viewer.teaching_text.content
        assert "the IMU-rate poses (small axes)" in viewer.teaching_text.content
    finally:
        viewer._set_overlay(OverlayColour.RESIDUAL.value)
        viewer.apply_layout_name("debug")


def test_recording_with_its_map_runs_the_tracker_and_exports_a_trajectory(viewer):
    assert viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, TrackerEngine)
    assert viewer.map_dropdown.value.endswith("squares_map.ply")
    assert viewer.time_slider.max == round(viewer.time_slider.max, 3)  # the end label in whole milliseconds
    for _ in range(5):
        viewer.player.step_forward()
    viewer.player.wait_idle()
    assert viewer.last_frame.index == 5 and viewer.last_frame.status == "ok"
    assert "TrackerConfig" in viewer.param_info.content or viewer.config_gui is not None
    assert ("registration", "robust_scale") in viewer.config_gui.handles
    # The viewer's tracking/SLAM switch and the tracker's own mode field are told apart by their labels.
    labels = [h.label for h in viewer.config_gui.handles.values()]
    assert "mode" in labels and viewer.mode_dropdown.label not in labels
    path = viewer.export("trajectory")
    assert path is not None and len([ln for ln in path.read_text().splitlines() if not ln.startswith("#")]) == 6
    assert viewer.export("config").read_text().startswith("mode:")


def test_parameters_the_tracker_cannot_start_with_keep_its_controls_so_they_can_be_moved_back(viewer):
    # A visible-map depth limit no map point passes: the tracker cannot start, the events-only view stands in.
    # Its controls replaced the tracker's, so the slider could not be moved back and the tuned values were lost.
    assert viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.wait_idle()
    tuned, depth = viewer.config_gui.handles[("rate_hz",)], viewer.config_gui.handles[("visible_map", "max_depth_m")]
    tuned.value = 150.0
    viewer.player.wait_idle()
    depth.value = depth.min
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, EventsOnlyEngine)
    assert viewer.config_gui.handles[("visible_map", "max_depth_m")] is depth and depth.value == depth.min
    assert "Tracking cannot start" in viewer.param_info.content and "Change the parameters" in viewer.param_info.content
    depth.value = 1000.0
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, TrackerEngine)
    assert viewer.player.engine.config.rate_hz == 150.0 and viewer.player.engine.config.visible_map.max_depth_m == 1000.0
    viewer.config_gui.reset()
    viewer.player.wait_idle()


def test_recording_without_a_map_shows_events_and_says_tracking_needs_one(viewer):
    bar = next(e.display for e in viewer.entries if e.path.name == "bar.h5")
    assert viewer.select(bar, NO_MAP)
    viewer.player.step_forward()
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, EventsOnlyEngine)
    assert "Tracking needs a map" in viewer.rec_info.content
    assert viewer.last_frame.ts_positive.max() > 0.5
    assert viewer.export("trajectory") is None and "no estimated poses" in viewer.export_info.content


def test_config_save_and_load_with_a_bad_file_name_say_why_in_the_panel(viewer):
    viewer.player.wait_idle()
    cases = {("save", "   "): "type a file name", ("load", ""): "type a file name",
             # An OSError (the name is too long) was a traceback on the console and nothing in the panel.
             ("save", "a" * 300 + ".yaml"): "File name too long",
             # A mistyped name of a saved file read "refused: outside the data directories".
             ("load", "no_such_saved.yaml"): "no such file in the export folder"}
    for (action, name), want in cases.items():
        viewer.config_path.value = name
        viewer._param_action(action)
        assert f"**{action} failed:**" in viewer.param_info.content and want in viewer.param_info.content, (name[:20], viewer.param_info.content)
        assert "\n" not in viewer.param_info.content
    assert not (viewer.cfg.export_dir / "   ").exists()
    # Only configuration names: with --export-dir on a data folder, "landing.h5" replaced the recording by YAML.
    recording = viewer.cfg.export_dir / "rec.h5"
    recording.write_bytes(b"recording bytes")
    viewer.config_path.value = "rec.h5"
    viewer._param_action("save")
    assert "**save failed:**" in viewer.param_info.content and recording.read_bytes() == b"recording bytes"
    viewer.config_path.value = "no_suffix"
    viewer._param_action("save")
    assert viewer.param_info.content == f"saved `{viewer.cfg.export_dir / 'no_suffix.yaml'}`"
    viewer.config_path.value = " saved.yaml "
    viewer._param_action("save")
    viewer._param_action("load")
    assert viewer.param_info.content.startswith("loaded") and (viewer.cfg.export_dir / "saved.yaml").is_file()


def test_screenshot_export_without_a_browser_fails_politely(viewer):
    assert viewer.export("screenshot") is None
    assert "connected browser" in viewer.export_info.content


def test_a_tab_closed_while_it_renders_an_export_ends_it_with_a_message(viewer):
    class ClosedTab:  # viser's client handle once its tab has gone away mid-render
        def get_render(self, **kwargs):
            raise RuntimeError("Render request failed: the client disconnected before returning a frame.")

    for what in ("screenshot", "GIF"):
        # It was a traceback on the server's console and every other tab kept reading "rendering ...".
        assert viewer.export(what, ClosedTab()) is None
        assert viewer.export_info.content.startswith(f"**{what} export failed:** the browser tab rendering it went away")


def test_a_speed_typed_past_the_sliders_ends_is_shown_as_the_speed_played(viewer):
    for typed, played in ((100.0, 10.0), (-1.0, 0.1), (2.0, 2.0), (1.0, 1.0)):
        viewer.speed_slider.value = typed  # as the slider's box sends it; it kept 100 while the player ran at 10x
        viewer.player.wait_idle()
        assert viewer.player.speed == viewer.speed_slider.value == played


def test_seek_answers_quickly_and_matches_the_step(viewer):
    sq = next(e.display for e in viewer.entries if e.path.name == "squares.h5")
    viewer.select(sq)
    viewer.player.wait_idle()
    t_target = viewer.recording.t_start_us + 300_000
    t0 = time.perf_counter()
    viewer.player.seek(t_target)
    viewer.player.wait_idle()
    assert viewer.last_frame.t_us <= t_target
    assert time.perf_counter() - t0 < 30  # correctness here; speed is reported by the benchmark, not asserted


def test_after_a_rescan_the_dropdowns_still_name_the_recording_shown_when_its_file_went_away(tmp_path, squares_scene):
    from app_scenes import write_data_root

    root = write_data_root(tmp_path, squares_scene)
    app = ViewerApp(AppConfig(data=[root], port=free_port(), export_dir=tmp_path / "exports",
                              player=PlayerConfig(prefetch=False)))
    try:
        assert app.select(next(e.display for e in app.entries if e.path.name == "squares.h5"))
        app.player.wait_idle()
        shown = app.rec_dropdown.value
        (root / "squares.h5").rename(root / "renamed.h5")
        app.refresh_entries()
        # It named the first recording found, which choosing then did not open (the value did not change).
        assert app.rec_dropdown.value == shown and app.map_dropdown.value.endswith("squares_map.ply")
        assert "shown from memory" in app.rec_info.content
        assert any(o.endswith("renamed.h5") for o in app.rec_dropdown.options)
    finally:
        app.stop()


def test_empty_data_folders_still_serve(tmp_path):
    app = ViewerApp(AppConfig(data=[tmp_path / "missing", tmp_path], port=free_port(), export_dir=tmp_path / "exp"))
    try:
        assert app.rec_dropdown.options == ("(none found)",) or list(app.rec_dropdown.options) == ["(none found)"]
        assert app.player is None
        assert "does not exist" in app.rec_info.content
    finally:
        app.stop()


def test_a_disk_cache_inside_a_data_folder_is_turned_off_and_the_reason_shown(tmp_path):
    from app.disk_cache import DiskCacheConfig

    app = ViewerApp(AppConfig(data=[tmp_path], port=free_port(), export_dir=tmp_path.parent / "exports_cache_note",
                              disk_cache=DiskCacheConfig(directory=tmp_path / "cache")))
    try:
        assert app.cfg.disk_cache.enabled is False and "inside the data folder" in app.rec_info.content
    finally:
        app.stop()
    assert not (tmp_path / "cache").exists()


def test_the_raw_cloud_is_read_only_when_shown_and_drawn_again_for_each_opening(tmp_path, squares_scene, monkeypatch):
    import numpy as np

    import app.server as server

    rec, cmap = squares_scene
    (tmp_path / "data").mkdir()
    write_recording_h5(tmp_path / "data" / "squares.h5", rec)
    write_contour_map(tmp_path / "data" / "squares_map.ply", cmap)
    pts = np.asarray(cmap.points, np.float64)
    (tmp_path / "data" / "squares_cloud.ply").write_text(
        f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        + "".join(f"{x} {y} {z}\n" for x, y, z in pts))
    reads = []
    real = server.load_cloud
    monkeypatch.setattr(server, "load_cloud", lambda path: reads.append(path.name) or real(path))
    app = ViewerApp(AppConfig(data=[tmp_path / "data"], port=free_port(), export_dir=tmp_path / "exports",
                              player=PlayerConfig(prefetch=False)))
    try:
        app.player.wait_idle()
        # Hidden (every shipped layout): not read, so opening a recording never waits for open3d's import.
        assert not app.scene.toggles.raw_cloud and reads == [] and "cloud" not in app.scene._nodes
        app._set_toggle("raw_cloud", True)
        app.player.wait_idle()
        assert reads == ["squares_cloud.ply"] and len(app.scene._nodes["cloud"].points) == len(pts)
        app._set_toggle("raw_cloud", False)
        app._set_toggle("raw_cloud", True)  # read once per opening
        assert app.select(app.rec_dropdown.value)  # reopening clears the scene, then draws the cloud again
        app.player.wait_idle()
        assert reads == ["squares_cloud.ply"] * 2 and "cloud" in app.scene._nodes
    finally:
        app.stop()


def test_a_recording_without_imu_opened_first_shows_the_trackers_controls_to_set_its_mode(tmp_path, squares_scene):
    # Tracking in mode "full" needs an IMU: the events-only view stood in with its own controls and the note said
    # "use --mode stpe", a command-line flag; no control of the viewer could set the mode.
    import dataclasses

    from evpose.tracker.config import TrackerConfig

    rec, cmap = squares_scene
    write_recording_h5(tmp_path / "squares.h5", dataclasses.replace(rec, imu=None, source=None))
    write_contour_map(tmp_path / "squares_map.ply", cmap)
    app = ViewerApp(AppConfig(data=[tmp_path], port=free_port(), export_dir=tmp_path / "exports",
                              player=PlayerConfig(prefetch=False)))
    try:
        app.player.wait_idle()
        assert isinstance(app.player.engine, EventsOnlyEngine) and app.config_gui.cls is TrackerConfig
        assert "set **mode** to stpe in the parameters below" in app.param_info.content and "--mode" not in app.param_info.content
        assert "Change the parameters below" in app.param_info.content  # the note sits above the controls
        app.config_gui.handles[("mode",)].value = "stpe"
        app.player.wait_idle(60)
        assert isinstance(app.player.engine, TrackerEngine) and app.player.engine.config.mode.value == "stpe"
    finally:
        app.stop()


def test_every_control_of_the_main_and_teaching_panels_has_hover_help(viewer):
    # The 3D view has no legend: its checkboxes had no hint but "slam aligned", the colours were told nowhere else
    # than the teaching panel's fusion stage; the overlay, stage, re-run, layout and export controls had none.
    from app.scene import SceneToggles

    assert set(viewer.toggle_boxes) == set(vars(SceneToggles()))
    for name, box in viewer.toggle_boxes.items():
        assert box.hint, name
    for name in ("fused", "registration", "ground_truth", "frustum"):
        assert "(" in viewer.toggle_boxes[name].hint, f"{name}: its colour"
    for handle in (viewer.rec_dropdown, viewer.map_dropdown, viewer.mode_dropdown, viewer.rescan_button, viewer.play_button,
                   viewer.step_buttons, viewer.time_slider, viewer.speed_slider, viewer.loop_box, viewer.overlay_dropdown,
                   viewer.export_buttons, viewer.stage_dropdown, viewer.stage_buttons, viewer.rerun_dropdown,
                   viewer.param_buttons, viewer.config_path, viewer.layout_gui.dropdown, viewer.layout_gui.name_box,
                   viewer.bookmark_gui.title_box, viewer.bookmark_gui.save_button, viewer.bookmark_gui.dropdown,
                   viewer.bookmark_gui.actions):
        assert handle.hint, handle.label
    # And every other input of viser's: "save current layout" had none (session 29).
    handles = viewer.gui._gui_input_handle_from_uuid.values()  # viser keeps no public list of them
    assert len(handles) > 40 and sorted(h.label for h in handles if not h.hint) == []


def test_the_parameters_panel_says_what_it_holds_in_words_not_a_class_name(viewer):
    viewer.select(next(e.display for e in viewer.entries if e.path.name == "squares.h5"))
    viewer.player.wait_idle()
    assert isinstance(viewer.player.engine, TrackerEngine)
    assert "Config" not in viewer.param_info.content and "tracker's parameters" in viewer.param_info.content
