"""The narrow-window form of a layout (app/window_fit.py), without a browser."""

from app.layouts import CONTROL_PANEL_PX, LAYOUT_DIR, MIN_VIEW_PX, load_layout
from app.window_fit import FIT_BELOW_VIEW_PX, NARROW_COLUMN_PX, SLACK_PX, fitted, window_width


def test_a_layout_that_leaves_the_3d_view_room_is_placed_as_it_is():
    debug = load_layout(LAYOUT_DIR / "debug.json")
    assert fitted(debug, 1400) is debug and fitted(debug, None) is debug
    edges = sum(debug.region_widths().values())
    assert fitted(debug, edges + FIT_BELOW_VIEW_PX) is debug
    assert fitted(debug, edges + FIT_BELOW_VIEW_PX - 1) is not debug
    assert fitted(debug, edges + FIT_BELOW_VIEW_PX - SLACK_PX, SLACK_PX) is debug  # hysteresis
    # Wide panels on purpose (a 320 px view at 1400 px) are kept.
    data = debug.to_dict()
    data["panels"]["images"].update(dock="left", width=500)
    from app.layouts import Layout

    wide = Layout.from_dict(data)
    assert wide.view_width(1400) == 320 and fitted(wide, 1400) is wide


def test_a_narrow_window_puts_the_panels_in_one_right_column_leaving_the_3d_view_its_width():
    debug = load_layout(LAYOUT_DIR / "debug.json")  # images right, plots below images, parameters left
    narrow = fitted(debug, 1000)
    assert narrow is not debug
    assert narrow.placements() == [("images", "right"), ("plots", "below:images"), ("parameters", "below:plots")]
    assert narrow.region_widths() == {"left": CONTROL_PANEL_PX, "right": 1000 - CONTROL_PANEL_PX - MIN_VIEW_PX}
    assert narrow.view_width(1000) == MIN_VIEW_PX
    # Narrower still, the column keeps a readable width and the view gives way.
    assert fitted(debug, 800).region_widths()["right"] == NARROW_COLUMN_PX
    # The layout itself is untouched (it is what "save" writes and what a wider window gets back).
    assert debug.panels["parameters"].dock == "left" and debug.panels["images"].width == 340


def test_the_window_width_is_the_3d_view_plus_the_edges_placed():
    debug = load_layout(LAYOUT_DIR / "debug.json")
    assert window_width(360, debug) == 360 + sum(debug.region_widths().values())


def test_a_hidden_panel_stacked_on_a_moved_one_floats_until_shown():
    compare = load_layout(LAYOUT_DIR / "compare.json")  # plots right 460, images below plots
    data = compare.to_dict()
    data["panels"]["teaching"].update(visible=False, dock="below:images")
    from app.layouts import Layout

    narrow = fitted(Layout.from_dict(data), 900)
    assert narrow.panels["teaching"].dock == "float"
    assert narrow.placements() == [("plots", "right"), ("images", "below:plots")]


def test_the_column_keeps_the_layouts_top_to_bottom_order():
    # The teaching layout docks "How it works" above the images; the narrow form put it below them.
    teaching = load_layout(LAYOUT_DIR / "teaching.json")
    assert teaching.panels["teaching"].dock == "above:images"
    assert fitted(teaching, 900).placements() == [("teaching", "right"), ("images", "below:teaching")]
