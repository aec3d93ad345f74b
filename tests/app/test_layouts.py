"""Layout files: the shipped presets load, bad files are refused with the key, saving round-trips, docks resolve and edges are sized."""

import json

import pytest

from app.layout_gui import FLOAT_AT, FLOAT_DEFAULT
from app.layouts import (CONTROL_PANEL_PX, DEFAULT_COLUMN_PX, LAYOUT_DIR, MAX_WIDTH, MIN_VIEW_PX, MIN_WIDTH, NARROW_WINDOW_PX, Layout,
                         check_width, dock_choices, layout_path, list_layouts, load_layout, save_layout)
from evpose.errors import InputError


def test_shipped_layouts_load():
    found = list_layouts(LAYOUT_DIR)
    for name in ("debug", "teaching", "compare"):
        assert isinstance(found[name], Layout), found.get(name)
    assert found["teaching"].panels["teaching"].visible
    assert found["teaching"].scene.follow


def test_bad_layout_files_name_the_problem(tmp_path):
    cases = {
        "syntax": ("{", "not valid JSON"),
        "panel": (json.dumps({"name": "x", "panels": {"bogus": {}}}), "panels.bogus"),
        "dock": (json.dumps({"name": "x", "panels": {"plots": {"dock": "upside"}}}), "dock"),
        "scene": (json.dumps({"name": "x", "scene": {"lasers": True}}), "scene"),
    }
    for stem, (text, needle) in cases.items():
        (tmp_path / f"{stem}.json").write_text(text)
        with pytest.raises(InputError, match=needle):
            load_layout(tmp_path / f"{stem}.json")
    # Bytes that are not UTF-8 (a layout saved by another editor) raised UnicodeDecodeError out of list_layouts.
    (tmp_path / "latin.json").write_bytes(b'{"name": "caf\xe9"}')
    with pytest.raises(InputError, match="latin.json: not UTF-8 text"):
        load_layout(tmp_path / "latin.json")
    listed = list_layouts(tmp_path)
    assert set(listed) == set(cases) | {"latin"} and all(isinstance(v, str) for v in listed.values())


def test_saved_layout_round_trips(tmp_path):
    lay = load_layout(LAYOUT_DIR / "compare.json")
    lay.name = "mine"
    lay.scene.raw_cloud = True
    path = save_layout(lay, tmp_path)
    again = load_layout(path)
    assert again.to_dict() == lay.to_dict()


def test_layout_names_cannot_escape_the_folder(tmp_path):
    for bad in ("../evil", "a/b", "", "x" * 65):
        with pytest.raises(InputError):
            layout_path(bad, tmp_path)


def _debug():
    return load_layout(LAYOUT_DIR / "debug.json")


def test_a_panel_stacked_on_itself_or_in_a_circle_is_refused(tmp_path):
    (tmp_path / "self.json").write_text(json.dumps({"name": "x", "panels": {"plots": {"dock": "below:plots"}}}))
    with pytest.raises(InputError, match="panels.plots.*on itself"):
        load_layout(tmp_path / "self.json")
    lay = _debug()  # plots is below:images
    with pytest.raises(InputError, match="images -> plots -> images"):
        lay.with_dock("images", "above:plots")
    assert lay.panels["images"].dock == "right"  # the refused change left the layout alone


def test_dock_choices_offer_the_edges_and_every_other_panel_never_itself():
    choices = dock_choices("plots")
    assert choices[:3] == ["left", "right", "float"]
    assert "below:images" in choices and "above:parameters" in choices
    assert not any(c.endswith(":plots") for c in choices)
    lay = _debug()
    for c in choices:
        if c != "above:images" and c != "below:images":
            assert lay.with_dock("plots", c).panels["plots"].dock == c


def test_placements_put_anchors_first_and_panels_on_a_hidden_or_floating_anchor_take_its_place():
    lay = _debug()  # images right, plots below:images, parameters left, teaching hidden
    order = [p for p, _ in lay.placements()]
    assert order.index("images") < order.index("plots") and "teaching" not in order
    lay.panels["images"].visible = False
    assert dict(lay.placements())["plots"] == "right"  # where images would be
    lay = _debug().with_dock("images", "below:parameters")
    lay.panels["images"].visible = False
    assert dict(lay.placements())["plots"] == "below:parameters"
    lay = _debug().with_dock("images", "float")
    assert dict(lay.placements())["plots"] == "right"  # a stack needs a docked neighbour


def test_edge_widths_sum_the_columns_docked_there():
    lay = _debug()  # right: images with plots stacked in its column; left: main panel + parameters
    images, params = lay.panels["images"].width, lay.panels["parameters"].width
    assert lay.region_widths() == {"left": CONTROL_PANEL_PX + params, "right": images}
    lay = lay.with_dock("images", "left")
    assert lay.region_widths() == {"left": CONTROL_PANEL_PX + params + images, "right": 0}
    assert lay.view_width(1400) == 1400 - CONTROL_PANEL_PX - params - images
    lay.panels["images"].width = None
    assert lay.region_widths()["left"] == CONTROL_PANEL_PX + params + DEFAULT_COLUMN_PX


def test_shipped_layouts_leave_the_3d_view_room_in_a_narrow_window_and_float_inside_it():
    for name, lay in list_layouts(LAYOUT_DIR).items():
        view = lay.view_width(NARROW_WINDOW_PX)
        assert view >= MIN_VIEW_PX, (name, view)
        for panel, dock in lay.placements():
            if dock == "float":  # a floating panel opens inside the view, not over the docked panels
                x, _ = FLOAT_AT.get(panel, FLOAT_DEFAULT)
                assert abs(x) + (lay.panels[panel].width or DEFAULT_COLUMN_PX) <= view, (name, panel)


def test_widths_outside_the_range_or_not_whole_pixels_are_refused():
    assert check_width(None) is None and check_width(420.0) == 420
    for bad in (MIN_WIDTH - 1, MAX_WIDTH + 1, 400.5, "wide", True):
        with pytest.raises(InputError):
            check_width(bad)


def test_a_layout_can_start_the_teaching_panel_on_a_stage_and_refuses_an_unknown_one(tmp_path):
    # The teaching layout opened on the TDF, the third of six stages, where a lesson starts at the first.
    teaching = list_layouts(LAYOUT_DIR)["teaching"]
    assert teaching.stage == "events" and list_layouts(LAYOUT_DIR)["debug"].stage is None
    assert Layout.from_dict(json.loads(json.dumps(teaching.to_dict()))).stage == "events"
    with pytest.raises(InputError, match="stage 'tdf' is none of events, SP-TS, TDF"):
        Layout.from_dict({**teaching.to_dict(), "stage": "tdf"})


def test_saving_over_a_shipped_layout_in_the_shipped_folder_is_refused(tmp_path, monkeypatch):
    shipped = tmp_path / "layouts"
    shipped.mkdir()
    (shipped / "debug.json").write_text((LAYOUT_DIR / "debug.json").read_text())
    monkeypatch.setattr("app.layouts.LAYOUT_DIR", shipped)  # as if it were the checkout's layouts/
    before = (shipped / "debug.json").read_text()
    mine = load_layout(shipped / "debug.json")
    with pytest.raises(InputError, match="'debug' is a layout shipped with evpose: save under another name"):
        save_layout(mine, shipped)
    assert (shipped / "debug.json").read_text() == before
    assert save_layout(Layout.from_dict({**mine.to_dict(), "name": "my_debug"}), shipped) == shipped / "my_debug.json"
    other = tmp_path / "elsewhere"  # another --layout folder: its own files, any name
    assert save_layout(mine, other) == other / "debug.json"
