"""The viewer's Layout folder without a browser: width notes, saving what is shown and loading it back, docking and
sizing panels, and the edge widths sent again for a browser that drew the moves late (split out of test_server.py,
session 29, which had grown past 500 lines)."""

import socket
import time

from app.server import AppConfig, ViewerApp


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _app_with_copied_layouts(tmp_path):
    """A viewer over an empty data folder whose layout folder is a copy of the shipped presets."""
    from app.layouts import LAYOUT_DIR

    layouts = tmp_path / "layouts"
    layouts.mkdir()
    for f in LAYOUT_DIR.glob("*.json"):
        (layouts / f.name).write_text(f.read_text())
    (tmp_path / "data").mkdir()
    app = ViewerApp(AppConfig(data=[tmp_path / "data"], port=free_port(), layout_dir=layouts, export_dir=tmp_path / "exports"))
    return app, layouts


def test_a_refused_panel_width_note_goes_once_a_valid_width_is_set_and_a_layout_save_is_confirmed(tmp_path, monkeypatch):
    app, layouts = _app_with_copied_layouts(tmp_path)
    told = []
    monkeypatch.setattr(app.layout_gui, "_notify", lambda title, body, color="gray": told.append(body))
    try:
        assert not app.layout_gui.set_width("images", 50)
        assert "outside" in app.layout_gui.note.content
        assert app.layout_gui.set_width("images", 400)
        assert "outside" not in app.layout_gui.note.content  # it stayed up, as if 400 had been refused too
        assert app.layout_gui.save("mine") == layouts / "mine.json" and told == [f"saved {layouts / 'mine.json'}"]
    finally:
        app.stop()


def test_saving_the_layout_records_what_is_shown_at_run_time_and_loading_restores_it(tmp_path):
    from app.layouts import load_layout

    app, layouts = _app_with_copied_layouts(tmp_path)
    try:
        debug = load_layout(layouts / "debug.json")
        assert app.apply_layout_name("debug") and app.panels["plots"].visible
        app.set_panel_visible("plots", False)
        app.set_panel_visible("teaching", True)
        app._set_toggle("raw_cloud", True)
        app._set_toggle("slam_aligned", False)
        assert not app.panels["plots"].visible and not app.panel_boxes["plots"].value
        assert load_layout(layouts / "debug.json").to_dict() == debug.to_dict()  # the preset file is untouched
        path = app.save_current_layout("mine")
        saved = load_layout(path)
        assert not saved.panels["plots"].visible and saved.panels["teaching"].visible
        assert {k: (v.dock, v.width) for k, v in saved.panels.items()} == {k: (v.dock, v.width) for k, v in debug.panels.items()}
        assert saved.scene.raw_cloud and not saved.scene.slam_aligned and app.layout.name == "mine"
        assert app.apply_layout_name("teaching") and app.layout.name == "teaching"
        assert app.apply_layout_name("mine")
        assert not app.panels["plots"].visible and app.panels["teaching"].visible and not app.panel_boxes["plots"].value
        assert app.scene.toggles.raw_cloud and app.toggle_boxes["raw_cloud"].value and not app.scene.toggles.slam_aligned
        assert app.layout.to_dict() == saved.to_dict()
    finally:
        app.stop()


def test_the_layout_folder_docks_and_sizes_panels_and_a_saved_layout_restores_them(tmp_path):
    from app.layouts import load_layout

    app, layouts = _app_with_copied_layouts(tmp_path)
    lg = app.layout_gui
    try:
        assert app.apply_layout_name("debug")
        assert lg.docks["images"].value == "right" and lg.widths["images"].value == 340 and lg.widths["plots"].value == 0
        assert lg.set_dock("images", "left") and lg.set_width("images", 500)
        assert app.layout.panels["images"].dock == "left" and app.layout.panels["images"].width == 500
        assert lg.shown_docks["plots"] == "below:images"  # stacked on images, it went left with it
        # A circle is refused and the control shows the dock in effect; a width typed half-way is ignored.
        assert not lg.set_dock("images", "below:plots") and lg.docks["images"].value == "left"
        assert not lg.set_width("images", 50) and app.layout.panels["images"].width == 500
        app.set_panel_visible("images", False)
        assert lg.shown_docks == {"plots": "left", "parameters": "left"} and "images is hidden" in lg.note.content
        app.set_panel_visible("images", True)
        assert lg.set_dock("teaching", "float") and lg.set_width("teaching", 0)
        app.stage_dropdown.value = "registration"  # a lesson saved at a stage starts there again
        saved = load_layout(app.save_current_layout("moved"))
        assert saved.stage == "registration"
        assert (saved.panels["images"].dock, saved.panels["images"].width) == ("left", 500)
        assert (saved.panels["teaching"].dock, saved.panels["teaching"].width) == ("float", None)
        assert load_layout(layouts / "debug.json").panels["images"].dock == "right"  # the preset is untouched
        assert app.apply_layout_name("teaching") and lg.docks["images"].value == "right" and app.stage.value == "events"
        assert app.apply_layout_name("moved") and app.stage.value == "registration"
        assert lg.docks["images"].value == "left" and lg.widths["images"].value == 500 and lg.shown_docks["images"] == "left"
        assert app.layout.to_dict() == saved.to_dict()
    finally:
        app.stop()


def test_a_layout_change_sends_the_edge_widths_again_later_for_a_browser_that_drew_the_moves_late(tmp_path, monkeypatch):
    import app.layout_gui as layout_gui
    from browser_session import wait_for

    monkeypatch.setattr(layout_gui, "LATE_RESEND_S", (1.0, 1.5))
    app, _ = _app_with_copied_layouts(tmp_path)
    lg = app.layout_gui
    sent: list[float] = []
    late: list[list[float]] = []  # the widths each late resend sent
    try:
        # A tab, as the browser's connection would bring one (placement is sent to each tab, app/tab_placement.py).
        from types import SimpleNamespace

        conn = SimpleNamespace(queue_message=lambda m: None, get_message_buffer=lambda: SimpleNamespace(done=False))
        lg.client_connected(SimpleNamespace(client_id=7, _websock_connection=conn))
        monkeypatch.setattr(lg.tabs[7].placer, "set_width", lambda panel, w: sent.append(w))
        resend = lg._resend_edges

        def counted():
            before = len(sent)
            resend()
            late.append(sent[before:])

        monkeypatch.setattr(lg, "_resend_edges", counted)
        assert app.apply_layout_name("debug")
        wait_for(lambda: len(late) == len(layout_gui.LATE_RESEND_S), timeout=20, what="the late resends", detail=lambda: late)
        totals = app.layout.region_widths()
        # Each late resend sends both edges, each at its whole edge's width (viser shares it among the edge's columns).
        assert all(sorted(widths) == sorted([totals["left"], totals["right"]]) for widths in late)
        # A second change before they run restarts them instead of adding to them.
        late.clear()
        assert app.apply_layout_name("teaching") and app.apply_layout_name("debug")
        wait_for(lambda: len(late) == len(layout_gui.LATE_RESEND_S), timeout=20, what="the restarted late resends", detail=lambda: late)
        time.sleep(1.0)
        assert len(late) == len(layout_gui.LATE_RESEND_S)
    finally:
        app.stop()
