"""The viewer's controls: the left panel, the floating panels and the hotkeys, built on a :class:`~app.server.ViewerApp`.

Each control is stored on the viewer (``app.rec_dropdown``, ``app.image_handles``, ...) and wired to its methods; the
viewer calls these once, while it starts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from app.bookmark_gui import BookmarkGui
from app.engine_factory import MODES
from app.hotkeys import bind_hotkeys
from app.layout_gui import LayoutGui
from app.page_patch import add_page_patch
from app.panels import IMAGES_IN_SLAM_MODE, SLAM_PANELS, SLAM_PLACEHOLDER, TRACKER_PANELS, OverlayColour
from app.player import RerunFrom
from app.plots import PlotsView
from app.teaching import Stage, teaching_markdown

if TYPE_CHECKING:
    from app.server import ViewerApp

NO_MAP = "(no map: events only)"
TOGGLE_HINTS = {
    "contour_map": "The map's points: grey out of view, cyan in view, red / blue predicted ON / OFF, yellow in the buffer zone",
    "raw_cloud": "The scene's raw point cloud (*_cloud.ply beside the map), read when first shown",
    "ground_truth": "The true trajectory (green), when the recording has one",
    "registration": "The raw registrations, before fusion (purple)",
    "fused": "The fused trajectory, what the tracker outputs (orange)",
    "imu_poses": "IMU-rate poses since the last registration (small axes)",
    "frustum": "The camera at the shown pose (orange outline), the live TDF on its image plane",
    "follow": "Move every tab's camera with the tracked camera; untick to look around freely",
    "slam_aligned": "SLAM mode: place each map on the ground truth (Sim(3), evo's Umeyama); untick for the maps' own frames",
}
"""Hover text of the 3D view's checkboxes: the view has no legend, so each says what it draws and in which colour
(session 28: only "slam aligned" had one; the colours were told only in the teaching panel's fusion stage)."""
OTHER_HINTS = {
    "rescan": "Look through the --data folders again for recordings and maps added since",
    "overlay": "What colours the map points on the TDF image: residual (green on an edge, red far), weight (green "
               "counted fully, red down-weighted) or predicted polarity (red ON, blue OFF, yellow buffer zone)",
    "export": "Write to the export folder and download: trajectory (TUM), configuration (YAML), screenshot of the 3D "
              "view (PNG), short GIF of it",
    "stage": "The pipeline stage explained, from the events to fusion",
    "rerun": "Where a parameter change starts computing again: at the shown step (what a headless run with the new "
             "values shows there) or from the recording's start",
    "configuration": "reset: the defaults; save / load: the file named below",
}
"""Hover text of the other controls that had none (session 28)."""
PLAYBACK_HINTS = {
    "play": "Play or pause (Space). At the last step, play starts again from the beginning.",
    "step": "One step back or forward (arrow keys left / right, when no slider has the focus).",
    "time": "Time from the recording's start, seconds: drag or type to seek (Home: back to the start).",
    "speed": "Playback speed, times real time, 0.1-10 (arrow keys up / down: double / halve). Stretches without "
             "events are gone over at once.",
    "loop": "At the end, go on from the beginning instead of pausing.",
}
"""Hover text of the playback controls (what they do and their keys)."""


def build_main_panel(app: ViewerApp) -> None:
    """The left panel: recording / map / viewer mode, playback, 3D view toggles, layout and export controls."""
    g = app.gui
    g.main_panel.dock_left()
    add_page_patch(g)  # first, so it is in place before any image: app/page_patch.py
    with g.add_folder("Recording"):
        app.rec_dropdown = g.add_dropdown("recording", ["(none found)"], hint="Recordings under the --data folders")
        app.map_dropdown = g.add_dropdown("map", [NO_MAP], hint="Contour map to track against")
        # Not "mode": the tracker's own mode (full / stpe / stpe+filter) has that label in the Parameters panel.
        app.mode_dropdown = g.add_dropdown("viewer mode", list(MODES), initial_value=MODES[0], hint="tracking: EV-Pose against the map; slam: map-free event SLAM")
        app.rescan_button = g.add_button("rescan data folders", hint=OTHER_HINTS["rescan"])
        app.rec_info = g.add_markdown("")
    with g.add_folder("Playback"):
        # Hints: the playback controls had none, and their keys were listed only in the README and the command palette.
        app.play_button = g.add_button("play / pause (space)", hint=PLAYBACK_HINTS["play"])
        app.step_buttons = g.add_button_group("step", ["< back", "forward >"], hint=PLAYBACK_HINTS["step"])
        app.time_slider = g.add_slider("time [s]", min=0.0, max=1.0, step=0.001, initial_value=0.0, hint=PLAYBACK_HINTS["time"])
        app.speed_slider = g.add_slider("speed [x]", min=0.1, max=10.0, step=0.1, initial_value=1.0, hint=PLAYBACK_HINTS["speed"])
        app.loop_box = g.add_checkbox("loop", False, hint=PLAYBACK_HINTS["loop"])
        app.status = g.add_markdown("_no recording loaded_")
    # Below the playback controls: one line or more per recording found, it pushed them off a 900 px screen.
    app.warm_info = g.add_markdown("")
    with g.add_folder("3D view", expand_by_default=False):
        app.toggle_boxes = {}
        for name in ("contour_map", "raw_cloud", "ground_truth", "registration", "fused", "imu_poses", "frustum", "follow", "slam_aligned"):
            app.toggle_boxes[name] = g.add_checkbox(name.replace("_", " "), getattr(app.scene.toggles, name), hint=TOGGLE_HINTS.get(name))
        app.overlay_dropdown = g.add_dropdown("TDF points coloured by", [o.value for o in OverlayColour], initial_value=app.overlay.value,
                                               hint=OTHER_HINTS["overlay"])
    with g.add_folder("Layout", expand_by_default=False):
        app.layout_gui = LayoutGui(g, app.cfg.layout_dir, app._notify, app._layout_applied, app._redraw)
    with g.add_folder("Bookmarks", expand_by_default=False) as folder:  # a lesson's saved moments: app/bookmark_gui.py
        app.bookmark_gui = BookmarkGui(app, app.cfg.bookmarks_path(), folder)
    with g.add_folder("Export", expand_by_default=False):
        app.export_buttons = g.add_button_group("export", ["trajectory", "config", "screenshot", "GIF"], hint=OTHER_HINTS["export"])
        app.export_info = g.add_markdown("")
    _wire_main_panel(app)


def _wire_main_panel(app: ViewerApp) -> None:
    """Connect the left panel's controls to the viewer's methods."""
    app.rec_dropdown.on_update(lambda e: e.client is not None and app.select(app.rec_dropdown.value))
    app.map_dropdown.on_update(lambda e: e.client is not None and app.select(app.rec_dropdown.value, app.map_dropdown.value, keep_moment=True))
    app.mode_dropdown.on_update(lambda e: e.client is not None and app.set_mode(app.mode_dropdown.value))
    app.rescan_button.on_click(lambda e: app.refresh_entries())
    app.play_button.on_click(lambda e: app.player and app.player.toggle())
    app.step_buttons.on_click(lambda e: app.player and (app.player.step_back() if e.target.value == "< back" else app.player.step_forward()))
    app.time_slider.on_update(lambda e: e.client is not None and app._time_typed())
    app.speed_slider.on_update(lambda e: app._speed_changed())
    app.loop_box.on_update(lambda e: app.player and app.player.set_loop(app.loop_box.value))
    for name, box in app.toggle_boxes.items():
        box.on_update(lambda e, name=name, box=box: app._set_toggle(name, box.value))
    app.overlay_dropdown.on_update(lambda e: app._set_overlay(app.overlay_dropdown.value))
    app.export_buttons.on_click(lambda e: app.export(e.target.value, e.client))


def build_panels(app: ViewerApp) -> None:
    """The floating panels: images (tracker and SLAM), plots, "How it works" and parameters."""
    g = app.gui
    app.panels = {}
    app.panels["images"] = p = g.add_panel()
    blank = np.zeros((48, 64, 3), np.uint8)
    with p.add_tab("Images"):
        app.images_note = g.add_markdown(IMAGES_IN_SLAM_MODE, visible=False)
        app.image_handles = {name: g.add_image(blank, label=name, format="jpeg", jpeg_quality=85) for name in TRACKER_PANELS}
    with p.add_tab("SLAM"):
        app.slam_info = g.add_markdown(SLAM_PLACEHOLDER)
        app.image_handles.update({name: g.add_image(blank, label=name, format="jpeg", jpeg_quality=85) for name in SLAM_PANELS})
    app.panels["plots"] = p = g.add_panel()
    app.plots = PlotsView(g, p.add_tab("Plots"))
    app.panels["teaching"] = p = g.add_panel()
    with p.add_tab("How it works"):
        app.stage_dropdown = g.add_dropdown("stage", [s.value for s in Stage], initial_value=app.stage.value, hint=OTHER_HINTS["stage"])
        # A lesson walks the stages in order: the dropdown alone took two clicks and a look through the list per stage.
        app.stage_buttons = g.add_button_group("stages", ["< previous", "next >"], hint="The previous / next stage (after fusion: events again); keys PageUp / PageDown, as a presenter's clicker sends")
        # The live image above the text: under it, a 1280x720 projector showed only its top (app/teaching.py).
        app.teaching_image = g.add_image(blank, label="live image", format="jpeg")
        app.teaching_text = g.add_markdown(teaching_markdown(app.stage, None))
    app.stage_dropdown.on_update(lambda e: app._set_stage(app.stage_dropdown.value))
    app.stage_buttons.on_click(lambda e: app.step_stage(-1 if e.target.value == "< previous" else 1))
    app.panels["parameters"] = p = g.add_panel()
    app.params_tab = p.add_tab("Parameters")
    with app.params_tab:
        app.rerun_dropdown = g.add_dropdown("on change re-run from", [r.value for r in RerunFrom], initial_value=RerunFrom.CURRENT.value,
                                           hint=OTHER_HINTS["rerun"])
        app.param_buttons = g.add_button_group("configuration", ["reset", "save", "load"], hint=OTHER_HINTS["configuration"])
        app.config_path = g.add_text("config file", "evpose_exports/config.yaml", hint="A .yaml, .yml or .json file: save writes it to the export folder; load reads it from there or the data folders")
        app.param_info = g.add_markdown("")
    app.param_buttons.on_click(lambda e: app._param_action(e.target.value))


def bind_viewer_hotkeys(app: ViewerApp) -> None:
    """Keyboard shortcuts of the playback controls (sliders keep their own arrow keys, app/hotkeys.py)."""
    app.key_guard.watch([app.time_slider, app.speed_slider])
    bind_hotkeys(app.gui, (("play / pause", "space", lambda: app.player and app.player.toggle()),
                            ("step forward", "arrowright", lambda: app.player and app.player.step_forward()),
                            ("step back", "arrowleft", lambda: app.player and app.player.step_back()),
                            ("faster", "arrowup", lambda: app._nudge_speed(2.0)),
                            ("slower", "arrowdown", lambda: app._nudge_speed(0.5)),
                            ("to start", "home", lambda: app.player and app.player.seek(app.player.engine.t_start_us)),
                            # A presenter's clicker sends PageDown / PageUp: the lesson's next / previous stage.
                            ("next stage", "pagedown", lambda: app.step_stage(1)),
                            ("previous stage", "pageup", lambda: app.step_stage(-1))),
                 app.key_guard)
