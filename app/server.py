"""The viewer: a viser server composing the player, scene, panels, plots, parameters, browser, layouts and export.

One engine per server, owned by the player's worker thread; every browser tab
drives and sees that same session (commands are serialised through one queue,
so concurrent tabs cannot corrupt it). Per-tab state is only the 3D camera and where the panels are placed (app/layout_gui.py).
"""

from __future__ import annotations

import dataclasses
import threading
import time
from pathlib import Path

import numpy as np
import viser

from app.app_config import AppConfig, cache_inside_data, check_port_free
from app.browser import DataEntry, DataRoots, EntryKind, guess_map_for, load_cloud, load_map, load_recording, scan_note
from app.config_gui import ConfigGui
from app.engine import Engine
from app.engine_factory import MODES, NO_MAP_NOTE, engine_factory
from app.export import export_action
from app.frame import Frame
from app.hotkeys import SliderKeyGuard
from app.layouts import Layout
from app.panels import SLAM_PANELS, SLAM_PLACEHOLDER, TRACKER_PANELS, OverlayColour, panel_images
from app.param_panel import config_changed, param_action, rebuild_config_gui
from app.player import Player, PlayState
from app.plots import plot_context
from app.scene import SceneView
from app.slam_engine import slam_markdown
from app.status import event_gaps, status_markdown
from app.teaching import STAGE_PANEL, Stage, image_caption, live_image, stage_after, teaching_markdown
from app.viewer_controls import NO_MAP, bind_viewer_hotkeys, build_main_panel, build_panels
from app.warm_up import WarmUp
from app.window_fit import WindowWatch
from evpose.errors import EvposeError, InputError

__all__ = ["AppConfig", "ViewerApp"]

OPENING = "_opening "
"""How the status line starts while a recording's first step is computed."""
ERROR_NOTE = "**error:** "
"""How the status line's last paragraph starts when the player has failed since the step shown was drawn."""
SLOW_REFRESH_S = 0.25
"""While playing, plots and trajectory polylines refresh at most this often, seconds."""


class ViewerApp:
    """The running viewer."""

    def __init__(self, cfg: AppConfig):
        check_port_free(cfg.host, cfg.port)
        self.cache_note = cache_inside_data(cfg)
        """Why the disk cache is off, if it is (shown under the recording list)."""
        if self.cache_note:
            cfg = dataclasses.replace(cfg, disk_cache=dataclasses.replace(cfg.disk_cache, enabled=False))
        self.cfg = cfg
        self.roots = DataRoots(cfg.data)
        self.server = viser.ViserServer(host=cfg.host, port=cfg.port, label="evpose", verbose=False)
        self.gui = self.server.gui
        self.scene = SceneView(self.server)
        self.entries: list[DataEntry] = []
        self.recording = None
        self.contour_map = None
        self.player: Player | None = None
        self.config_gui: ConfigGui | None = None
        self.overlay = OverlayColour.RESIDUAL
        self.stage = Stage.TDF
        self.last_frame: Frame | None = None
        self._open_displays: tuple[str, str] | None = None
        """(recording, map) dropdown values of what is open."""
        self._shown_label = ""
        """Label of the recording the player works on (set on its thread when it gets to an opening)."""
        self.gaps: list = []
        """The shown recording's stretches without events (app/status.py: named in the status line)."""
        self._select_lock = threading.Lock()
        self._cloud_lock = threading.Lock()
        self._cloud_entry: DataEntry | None = None
        """Map entry of the open recording, whose raw cloud is read when first shown."""
        self._cloud_generation = 0
        """Counts openings, so a cloud read for an earlier one is not drawn over a later one."""
        self._cloud_read = -1
        """Opening whose cloud has been read (-1: none)."""
        self.frames_published = 0
        self._slam_panels_shown: bool | None = None
        """Whether the image panels shown are SLAM mode's (None: none drawn yet)."""
        self._last_slow = 0.0
        self.param_said = ""
        """What the Parameters panel's last button did, shown above the engine's note (app/param_panel.py)."""
        self.key_guard = SliderKeyGuard()
        """Arrow/Home shortcuts pressed on a focused slider move the slider only (app/hotkeys.py)."""
        build_main_panel(self)  # the controls: app/viewer_controls.py
        self.warm_up = WarmUp(cfg.disk_cache, cfg.frame_cache, lambda md: setattr(self.warm_info, "content", md),
                              cfg.warm_up, busy=self._player_busy)
        build_panels(self)
        self.layout_gui.panels = self.panels
        self.refresh_entries()
        self.apply_layout_name(cfg.layout)
        bind_viewer_hotkeys(self)
        self.window_watch = WindowWatch(self.server, self.layout_gui)
        """Fits the panels to each tab's window (app/window_fit.py)."""
        self.server.on_client_connect(lambda client: (self.layout_gui.client_connected(client), self.window_watch.watch(client)))
        self.server.on_client_disconnect(self.layout_gui.client_disconnected)
        recs = [e for e in self.entries if e.kind == EntryKind.RECORDING and e.error is None]
        if recs:
            # Open on the shortest-named landing recording (the showcase) when there is one, else the first found.
            with_map = [e for e in recs if e.path.stem.startswith("landing")]
            self.select((sorted(with_map, key=lambda e: len(e.path.stem)) or recs)[0].label)

    # ------------------------------------------------------------------ data
    def refresh_entries(self) -> None:
        self.entries = self.roots.scan()
        recs = [e for e in self.entries if e.kind == EntryKind.RECORDING]
        maps = [e for e in self.entries if e.kind == EntryKind.MAP]
        rec_options = [e.display for e in recs] or ["(none found)"]
        map_options = [NO_MAP] + [e.display for e in maps]
        gone = []
        if self._open_displays is not None:
            # The files of what is shown went away (renamed, deleted) before a rescan: the dropdowns fell back to
            # their first entry and named a recording that was not the one shown, which choosing did not open (no
            # change). They keep naming what is shown, said to be from memory.
            for options, shown in zip((rec_options, map_options), self._open_displays):
                if shown not in options:
                    options.append(shown)
                    gone.append(f"`{shown}`")
            if rec_options[0] == "(none found)" and len(rec_options) > 1:
                rec_options.pop(0)
        self.rec_dropdown.options = rec_options
        self.map_dropdown.options = map_options
        if self._open_displays is not None:
            self.rec_dropdown.value, self.map_dropdown.value = self._open_displays
        self.rec_info.content = ((f"_{' and '.join(gone)}: shown from memory, no longer found under the data folders._\n\n"
                                  if gone else "") + self._scan_note())
        self.warm_up.start(self.entries)

    def _scan_note(self) -> str:
        return scan_note(self.entries, self.roots, self.cache_note)

    def _entry(self, display: str) -> DataEntry | None:
        for e in self.entries:
            if display in (e.display, e.label):
                return e
        return None

    @property
    def mode(self) -> str:
        return self.mode_dropdown.value

    def set_mode(self, mode: str) -> bool:
        """Switch between tracking and SLAM on the loaded recording (and map)."""
        if mode not in MODES:
            return False
        self.mode_dropdown.value = mode
        map_display = self.map_dropdown.value if self.map_dropdown.value in self.map_dropdown.options else None
        return self.select(self.rec_dropdown.value, map_display, keep_moment=True)

    def select(self, rec_display: str, map_display: str | None = None, keep_moment: bool = False) -> bool:
        """Load a recording (and a map, guessed if not given); errors are shown, never raised to the server.

        ``keep_moment``: when it is the recording shown (another viewer mode or map), go on at the time shown, not at
        its start. Session 29: switching to SLAM at 2.5 s of landing showed its first step, the time slider back at 0
        with no word why, and the moment being looked at had to be found again (SLAM computes up to it, with the
        "computing ... to reach the seek" line; a seek elsewhere or pause gives that up)."""
        with self._select_lock:  # two tabs switching at once load one after the other
            return self._select(rec_display, map_display, keep_moment)

    def _moment_shown(self, entry: DataEntry) -> int | None:
        """Microseconds from the start of the step shown, if it is of ``entry``'s recording (else None)."""
        frame, player = self.last_frame, self.player
        if frame is None or player is None or self._open_displays is None or self._shown_label != entry.label:
            return None
        return max(0, int(frame.t_us - player.engine.t_start_us))

    def _select(self, rec_display: str, map_display: str | None, keep_moment: bool = False) -> bool:
        entry = self._entry(rec_display)
        if entry is None or entry.kind != EntryKind.RECORDING:
            return False
        try:
            if entry.error:
                raise InputError(entry.path, entry.error)
            path = self.roots.check(entry.path)
            recording = load_recording(path)
            maps = [e for e in self.entries if e.kind == EntryKind.MAP]
            if map_display is None:
                map_entry = guess_map_for(entry, maps, recording.metadata)
            else:
                map_entry = None if map_display == NO_MAP else self._entry(map_display)
            if map_entry is not None and map_entry.error:
                raise InputError(map_entry.path, map_entry.error)
            cmap = load_map(self.roots.check(map_entry.path)) if map_entry is not None else None
        except EvposeError as exc:
            self.rec_info.content = f"**Cannot open:** {exc}\n\n" + self._scan_note()
            self._notify("cannot open", str(exc), "red")
            if self._open_displays is not None:  # the dropdowns name what is still shown, not the refused file
                self.rec_dropdown.value, self.map_dropdown.value = self._open_displays
            return False
        moment_us = self._moment_shown(entry) if keep_moment else None
        self.rec_dropdown.value = entry.display
        self.map_dropdown.value = map_entry.display if map_entry is not None else NO_MAP
        self._open_displays = (self.rec_dropdown.value, self.map_dropdown.value)
        opening = f"{OPENING}`{entry.label}`: computing its first step..._"
        if self.player is not None and self.player.computing and self.recording is not None:
            # The player finishes what it computes first (a first step loads the compiled kernels: 0.3 s, a minute or
            # more on a cold numba cache, and cannot be interrupted; the next recording needs the same kernels anyway).
            of = f" of `{self._shown_label}`" if self._shown_label else ""
            self.status.content = (f"{OPENING}`{entry.label}`: waiting for the step{of} being computed to finish "
                                   "(a first step loads the compiled kernels: up to a minute or more on a cold cache)..._")
            self.param_info.content = (f"Opening `{entry.label}` once the player is free: the parameters below are "
                                       f"still those{of or ' of the recording shown'}.")
        else:
            self.status.content = opening  # until its first step is drawn
        s = recording.summary()
        self.rec_info.content = (f"`{entry.label}`: {s['events']:,} events, {s['duration_s']:.2f} s, "
                                 f"{s['sensor_size']}; map: {map_entry.label if map_entry else 'none'}"
                                 + ("" if cmap is not None or self.mode == "slam" else f"\n\n_{NO_MAP_NOTE}_") + "\n\n" + self._scan_note())
        self.warm_up.opened(path if self.mode == "tracking" and cmap is not None else None)
        # Whole milliseconds, the slider's step: the end label read "3.999952" (engines clip a seek past the end).
        self.time_slider.max = max(0.001, round((recording.t_end_us - recording.t_start_us) / 1e6, 3))
        gaps = event_gaps(recording.events.t)
        factory = engine_factory(recording, cmap, self.mode, self.cfg.frame_cache, self.cfg.disk_cache,
                                 (path, map_entry.path) if map_entry is not None else None)

        def reset_view(_engine=None):
            # Runs on the player thread (or before it exists) so no frame of the old recording is drawn over it.
            self.status.content = opening  # the player has got to it
            self.recording, self.contour_map, self._shown_label, self.gaps = recording, cmap, entry.label, gaps
            self.scene.load(cmap, None, recording.ground_truth, recording.calibration)
            self.scene.apply_toggles()
            self.plots.clear()

        if self.player is None:
            reset_view()
            self.player = Player(factory, self._on_frame, player_config=self.cfg.player,
                                 on_error=self._player_error,
                                 on_engine=self._rebuild_config_gui, on_progress=self._on_progress)
            self._rebuild_config_gui(self.player.engine)
            self.player.seek(recording.t_start_us)
        else:
            self.player.call(reset_view)
            # Keep the user's tuned parameters across recordings when the engine kind stays the same.
            self.player.load(factory, self.config_gui.config if self.config_gui is not None else None)
            if moment_us:  # on the player's thread, after the load: the time is from the start of the engine it loads
                player = self.player
                player.call(lambda engine: player.seek(engine.t_start_us + moment_us, exact=True))
        with self._cloud_lock:
            self._cloud_entry, self._cloud_generation = map_entry, self._cloud_generation + 1
        self._ensure_cloud()
        return True

    def _player_error(self, message: str) -> None:
        self._notify("viewer", message, "red")
        if self.status.content.startswith(OPENING):  # the first step failed: no frame will replace the note
            self.status.content = f"**could not show its first step:** {message}"
        else:
            # The notification closes after 6 s; the status line then read "paused" with no reason (robust loss
            # "tukey": "seek failed: Singular matrix"). It keeps the latest error until the next step is drawn.
            base = self.status.content.split(ERROR_NOTE)[0].rstrip()
            self.status.content = f"{base}\n\n{ERROR_NOTE}{message}"

    def _player_busy(self) -> bool:
        """Playing, computing a seek or running ahead: the warm-up holds still, so it takes no core from the player."""
        return self.player is not None and self.player.busy

    def _ensure_cloud(self) -> None:
        """Read and draw the open map's raw cloud when it is to be shown and is not drawn yet.

        Only then: the first read imports open3d (0.5-2.4 s measured), which at start delayed the
        run-ahead while the cloud, hidden in every shipped layout, was not even shown.
        """
        with self._cloud_lock:
            entry, gen = self._cloud_entry, self._cloud_generation
            if entry is None or self.player is None or not self.scene.toggles.raw_cloud or self._cloud_read == gen:
                return
            self._cloud_read = gen
        cloud = self._cloud_for(entry)
        if cloud is not None:
            # On the player thread, so it lands after reset_view (which clears the scene), and only for the same opening.
            self.player.call(lambda _engine: gen == self._cloud_generation and self.scene.set_cloud(cloud))

    def _cloud_for(self, map_entry: DataEntry | None):
        if map_entry is None:
            return None
        stem = map_entry.path.name.lower().removesuffix("_map.ply").removesuffix(".ply")
        for e in self.entries:
            if e.kind == EntryKind.CLOUD and e.error is None and e.path.name.lower().startswith(stem):
                try:
                    return load_cloud(e.path)
                except EvposeError:
                    return None
        return None

    # ------------------------------------------------------------------ per-step drawing (player thread)
    def _on_frame(self, frame: Frame, engine: Engine) -> None:
        # Images of hidden panels are neither drawn nor sent.
        show_images = self.layout is None or self.layout.panels["images"].visible
        show_teaching = self.layout is None or self.layout.panels["teaching"].visible
        imgs = panel_images(frame, self.overlay) if (show_images or show_teaching) else {}
        # Plots and trajectories change slowly: while playing they refresh a few times a second.
        now = time.monotonic()
        slow = self.player is None or self.player.state != PlayState.PLAYING or now - self._last_slow >= SLOW_REFRESH_S
        history = engine.history if slow else []
        with self.server.atomic():
            self._show_mode_panels(frame.slam is not None)
            for name, img in imgs.items() if show_images else ():
                self.image_handles[name].image = img
            self.scene.update(frame, history if slow else None)
            if slow:
                self._last_slow = now
                self.plots.update(history, self.recording.ground_truth if self.recording is not None else None,
                                  *plot_context(frame, engine), t0_us=engine.t_start_us)
            if frame.slam is not None:
                self.slam_info.content = slam_markdown(frame, self.scene.toggles.slam_aligned, engine.t_start_us)
            if show_teaching and (STAGE_PANEL[self.stage] in imgs or frame.slam is not None):
                # SLAM mode: the stages are the tracker's, which is not running; the text says so (no live image).
                self.teaching_text.content = teaching_markdown(self.stage, frame, engine.t_start_us, self.scene.toggles)
                if frame.slam is None:
                    self.teaching_image.image = live_image(self.stage, frame, imgs, self.overlay)
                    if self.teaching_image.label != (caption := image_caption(self.stage, frame)):
                        self.teaching_image.label = caption
            self.time_slider.value = round((frame.t_us - engine.t_start_us) / 1e6, 3)
            self.status.content = status_markdown(frame, engine, self.player.stats() if self.player else {}, self.gaps)
        self.frames_published += 1
        self.last_frame = frame  # last, so whoever sees it also sees everything drawn for it

    def _show_mode_panels(self, slam: bool) -> None:
        """Show the image panels of the mode the frames come from and hide the other mode's, which would stay
        frozen at the last step of that mode (the tracker's time surfaces seen beside SLAM's, as if they were live)."""
        if slam == self._slam_panels_shown:
            return
        self._slam_panels_shown = slam
        self.images_note.visible = slam
        self.teaching_image.visible = not slam
        for name in TRACKER_PANELS:
            self.image_handles[name].visible = not slam
        for name in SLAM_PANELS:
            self.image_handles[name].visible = slam
        if not slam:
            self.slam_info.content = SLAM_PLACEHOLDER

    def _on_progress(self, engine: Engine) -> None:
        # While paused the run-ahead advances without new frames: refresh the status line alone.
        if self.last_frame is not None and self.player is not None:
            self.status.content = status_markdown(self.last_frame, engine, self.player.stats(), self.gaps)

    # ------------------------------------------------------------------ parameters panel (app/param_panel.py)
    def _rebuild_config_gui(self, engine: Engine) -> None:
        rebuild_config_gui(self, engine)

    def _config_changed(self, config) -> None:
        config_changed(self, config)

    def _param_action(self, action: str) -> None:
        param_action(self, action)

    # ------------------------------------------------------------------ view options
    def _set_toggle(self, name: str, value: bool) -> None:
        setattr(self.scene.toggles, name, bool(value))
        if self.layout is not None:
            setattr(self.layout.scene, name, bool(value))
        self.scene.apply_toggles()
        if name == "raw_cloud" and value:
            self._ensure_cloud()
        if name == "slam_aligned":
            self._redraw()  # the SLAM maps move between the ground truth's frame and their own
        elif self.last_frame is not None and self.player is not None:  # the teaching text names what the view hides
            self.teaching_text.content = teaching_markdown(self.stage, self.last_frame, self.player.engine.t_start_us, self.scene.toggles)

    def _set_overlay(self, value: str) -> None:
        self.overlay = OverlayColour(value)
        self._redraw()

    def _set_stage(self, value: str) -> None:
        self.stage = Stage(value)
        if self.layout is not None:
            self.layout.stage = self.stage.value  # "save" keeps it
        self._redraw()

    def step_stage(self, delta: int) -> None:
        """The teaching panel's previous (-1) / next (+1) stage, in the lesson's order (the dropdown's callback redraws)."""
        self.stage_dropdown.value = stage_after(self.stage, delta).value

    def _redraw(self) -> None:
        if self.player is not None and self.last_frame is not None:
            frame = self.last_frame
            self.player.call(lambda eng: self._on_frame(frame, eng))

    def _speed_changed(self) -> None:
        value = self.speed_slider.value
        speed = float(np.clip(value, self.speed_slider.min, self.speed_slider.max))
        if speed != value:
            # Typed into the box past an end (100, 0, -1): the box kept it while the player ran at 10x or 0.1x.
            self.speed_slider.value = speed  # calls back here at once with the clamped speed
            return
        if self.player is not None:
            self.player.set_speed(speed)

    def _time_typed(self) -> None:
        """Seek to the time slider's value, a value typed past either end brought inside it first."""
        value = self.time_slider.value
        seconds = float(np.clip(value, 0.0, self.time_slider.max))
        if seconds != value:
            # "100" typed in a 4 s recording: the box kept showing 100 while SLAM computed up to the last step (tens of
            # seconds) and the engine clipped the seek. The write back does not seek again (no client: not a user's).
            self.time_slider.value = seconds
        if self.player is not None:
            self.player.seek(self._slider_to_us(seconds))

    def _nudge_speed(self, factor: float) -> None:
        self.speed_slider.value = float(np.clip(round(self.speed_slider.value * factor, 1), 0.1, 10.0))

    def _slider_to_us(self, seconds: float) -> int:
        t0 = self.recording.t_start_us if self.recording is not None else 0
        return int(round(t0 + seconds * 1e6))

    def _notify(self, title: str, body: str, color: str = "gray") -> None:
        for client in self.server.get_clients().values():
            client.add_notification(title, body, auto_close_seconds=6.0, color=color)

    # ------------------------------------------------------------------ layouts (app/layout_gui.py)
    @property
    def layout(self) -> Layout | None:
        """The layout as shown now (run-time changes included)."""
        return self.layout_gui.layout

    @property
    def panel_boxes(self) -> dict:
        return self.layout_gui.boxes

    def apply_layout_name(self, name: str) -> bool:
        return self.layout_gui.apply_name(name)

    def apply_layout(self, layout: Layout) -> None:
        self.layout_gui.apply(layout)

    def set_panel_visible(self, name: str, visible: bool) -> None:
        self.layout_gui.set_visible(name, visible)

    def save_current_layout(self, name: str, client=None) -> Path | None:
        return self.layout_gui.save(name)

    def _layout_applied(self, layout: Layout) -> None:
        self.gui.configure_theme(dark_mode=layout.dark_mode, show_share_button=False, control_width="medium")
        for name, box in self.toggle_boxes.items():
            box.value = getattr(layout.scene, name)
        self.scene.toggles = type(layout.scene)(**vars(layout.scene))
        self.scene.apply_toggles()
        if layout.stage is not None:
            self.stage_dropdown.value = layout.stage
        self._ensure_cloud()

    # ------------------------------------------------------------------ export
    def export(self, what: str, client=None) -> Path | None:
        try:
            path = export_action(self, what, client)
        except (EvposeError, ValueError, TimeoutError, OSError) as exc:
            self.export_info.content = f"**{what} export failed:** {exc}"
            return None
        self.export_info.content = f"wrote `{path}`"
        if client is not None and path is not None:
            client.send_file_download(path.name, path.read_bytes())
        return path

    def stop(self) -> None:
        self.warm_up.stop()
        self.layout_gui.stop()
        self.window_watch.stop()
        if self.player is not None:
            self.player.stop()
        self.server.stop()
