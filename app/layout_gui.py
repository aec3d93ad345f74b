"""The Layout folder: switch layouts, show/hide, dock and size each panel, save what is shown.

viser's panel placement is write-only: ``dock_*``/``float``/``set_width`` are commands, and a
panel the user drags in the browser stays there on screen but is never reported back to the
server. So the placement a saved layout records is the one set here, through these controls,
and applying it re-sends the commands to every tab.

Each tab is placed on its own (:class:`Tab`, sent through app/tab_placement.py): the layout, or
its narrow-window form when that tab's window is narrow (app/window_fit.py). Until session 27
the commands were viser's broadcasts, and the narrowest tab's fit was placed in every tab.
"""

from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from app.layouts import MAX_WIDTH, MIN_WIDTH, PANELS, Layout, check_width, dock_anchor, dock_choices, list_layouts, save_layout
from app.tab_placement import BroadcastPlacer, TabPlacer, placer_for
from app.window_fit import JITTER_PX, SLACK_PX, fitted
from evpose.errors import EvposeError, InputError

FLOAT_AT = {"teaching": (60, 15)}
"""Where a floating panel opens, CSS pixels from the canvas's top-left (negative x: from the right)."""
FLOAT_DEFAULT = (-15, 15)
RESEND_S = 0.4
"""Delay before an edge's width is sent again, seconds (see LayoutGui._size_edges)."""
LATE_RESEND_S = (1.5, 4.0)
"""Further sends of the edges' widths after a tab connects or a layout moves panels, seconds: on a loaded machine the
browser may draw its panels after RESEND_S and drop both earlier sends (a new tab's 3D view at 307 px in 2 of 6
full-suite runs; session 21, the debug layout's at 328 px in a full suite beside another experiment)."""


@dataclass
class Tab:
    """One open browser tab as placed: its window and the docks it was last sent."""

    placer: TabPlacer | BroadcastPlacer
    window_px: int | None = None
    """Its window's width, CSS px (None: not reported yet); app/window_fit.py."""
    narrow: bool = False
    """Whether it shows the layout's narrow-window form (the fit's hysteresis depends on it)."""
    shown_docks: dict[str, str] = field(default_factory=dict)
    """Panel -> dock last sent to this tab."""


class LayoutGui:
    """The Layout folder's controls and the current :class:`Layout` (a copy: run-time changes never touch the file)."""

    def __init__(self, gui, layout_dir: Path, notify: Callable[[str, str, str], None],
                 on_applied: Callable[[Layout], None], on_shown: Callable[[], None]):
        self.gui = gui
        self.layout_dir = layout_dir
        self._notify = notify
        self._on_applied = on_applied
        """Called with each applied layout (dark mode and the 3D toggles are the viewer's)."""
        self._on_shown = on_shown
        """Called when a panel is shown (images of hidden panels were neither drawn nor sent)."""
        self.layout: Layout | None = None
        self.tabs: dict[int, Tab] = {}
        """Client id -> the open tab (app/window_fit.py reports each one's window)."""
        self._tabs_lock = threading.Lock()
        self.panels: dict = {}
        self._timer: threading.Timer | None = None
        self._late_timers: list[threading.Timer] = []
        self._timer_lock = threading.Lock()
        self._stopped = False
        self.shown_docks: dict[str, str] = {}
        """Panel -> dock in a window wide enough for the layout (differs from the layout's when its anchor is hidden or
        floats); each tab's own are in :attr:`tabs`."""
        self.dropdown = gui.add_dropdown("layout", ["debug"], hint="Which panels are shown, where, and what the 3D view shows (layouts/*.json)")
        self.boxes, self.docks, self.widths = {}, {}, {}
        for name in PANELS:
            with gui.add_folder(f"{name} panel", expand_by_default=False):
                self.boxes[name] = gui.add_checkbox(f"show {name}", True, hint=f"Show the {name} panel (saved with the layout)")
                self.docks[name] = gui.add_dropdown(
                    f"{name} dock", dock_choices(name), initial_value="right",
                    hint="Where the panel goes, for every open tab; a panel dragged in the browser is not seen by the server, set it here to save it")
                self.widths[name] = gui.add_number(
                    f"{name} width [px]", 0, min=0, max=MAX_WIDTH, step=10,
                    hint=f"{MIN_WIDTH}-{MAX_WIDTH} px; 0 leaves the width to the viewer")
        self.note = gui.add_markdown("")
        self.name_box = gui.add_text("save as", "my_layout", hint="Name of the layout file the button below writes (layouts/<name>.json)")
        # The one control of the left panel without hover text (session 29).
        self.save_button = gui.add_button("save current layout", hint="Write the panels as shown (placed, sized, hidden), "
                                          "the 3D view's checkboxes and the teaching stage to layouts/<name above>.json; "
                                          "it is then listed under 'layout'")
        self.dropdown.on_update(lambda e: e.client is not None and self.apply_name(self.dropdown.value))
        self.save_button.on_click(lambda e: self.save(self.name_box.value))
        for name in PANELS:
            # Only a user's change acts: the values written here by apply() must not echo back.
            self.boxes[name].on_update(lambda e, n=name: e.client is not None and self.set_visible(n, self.boxes[n].value))
            self.docks[name].on_update(lambda e, n=name: e.client is not None and self.set_dock(n, self.docks[n].value))
            self.widths[name].on_update(lambda e, n=name: e.client is not None and self.set_width(n, self.widths[n].value))

    # ------------------------------------------------------------------ applying
    def available(self) -> dict:
        return list_layouts(self.layout_dir)

    def apply_name(self, name: str) -> bool:
        found = self.available()
        self.dropdown.options = sorted(k for k, v in found.items() if isinstance(v, Layout)) or ["debug"]
        layout = found.get(name)
        if not isinstance(layout, Layout):
            if isinstance(layout, str):
                self._notify("layout", layout, "red")
            layout = found.get("debug") if isinstance(found.get("debug"), Layout) else Layout("debug")
        self.apply(layout)
        return True

    def apply(self, layout: Layout) -> None:
        self.layout = Layout.from_dict(layout.to_dict())
        for name in PANELS:
            place = self.layout.panels[name]
            self.boxes[name].value = place.visible
            self.docks[name].value = place.dock
            self.widths[name].value = place.width or 0
            self.panels[name].visible = place.visible
        self.shown_docks = {}
        for tab in self._open_tabs():
            tab.shown_docks = {}
        self._on_applied(self.layout)  # first: the theme sets the main panel's width, the edge widths below include it
        self._place(set(PANELS))
        if layout.name in self.dropdown.options:
            self.dropdown.value = layout.name
        self._on_shown()  # panels hidden until now (e.g. teaching) were not drawn: draw the shown step into them

    def _open_tabs(self) -> list[Tab]:
        with self._tabs_lock:
            return list(self.tabs.values())

    def _place(self, touched: set[str]) -> None:
        """Place the touched panels, those whose shown dock changed, and everything stacked on those, in every tab."""
        self.shown_docks = dict(self.layout.placements())
        for tab in self._open_tabs():
            self._place_tab(tab, touched)
        self._describe(self.shown_docks)

    def _place_tab(self, tab: Tab, touched: set[str]) -> None:
        placed = self.placed(tab)
        tab.narrow = placed is not self.layout
        placements = placed.placements()
        moved = set(touched) | {p for p, dock in placements if tab.shown_docks.get(p) != dock}
        send = tab.placer
        for name, dock in placements:  # anchors come first, so a panel follows an anchor moved just before it
            if name not in moved and dock_anchor(dock) not in moved:
                continue
            moved.add(name)
            panel, width = self.panels[name], placed.panels[name].width
            if dock == "left":
                send.dock_left(panel)
            elif dock == "right":
                send.dock_right(panel)
            elif dock == "float":
                x, y = FLOAT_AT.get(name, FLOAT_DEFAULT)
                send.float(panel, x, y, width)
            else:
                where, anchor = dock.split(":")
                send.dock_beside(panel, where, self.panels[anchor])
        tab.shown_docks = dict(placements)  # visible panels only: hidden ones are re-placed when shown
        self._size_edges({self._edge(p, tab.shown_docks) for p in moved if p in tab.shown_docks} & {"left", "right"}, tabs=[tab])

    def placed(self, tab: Tab | None = None) -> Layout:
        """The layout as placed in ``tab``: the current one, or its narrow-window form (app/window_fit.py); without a
        tab, the layout as placed in a window wide enough for it."""
        if tab is None:
            return self.layout
        return fitted(self.layout, tab.window_px, -SLACK_PX if tab.narrow else SLACK_PX)

    def set_window_width(self, client_id: int, px: int) -> bool:
        """The tab ``client_id``'s window is ``px`` wide: place the layout fitted to it there if that changes anything."""
        tab = self.tabs.get(client_id)
        if self.layout is None or tab is None or (tab.window_px is not None and abs(px - tab.window_px) < JITTER_PX):
            return False
        before = self.placed(tab)
        tab.window_px = px
        after = self.placed(tab)
        tab.narrow = after is not self.layout
        if (before.placements(), before.region_widths()) == (after.placements(), after.region_widths()):
            self._describe(self.shown_docks)
            return False
        self._place_tab(tab, set())
        self._size_edges({"left", "right"}, tabs=[tab])
        self._describe(self.shown_docks)
        return True

    def _edge(self, name: str, shown: dict[str, str] | None = None) -> str:
        """Where the column holding a (visible) panel is: 'left', 'right' or 'float'."""
        shown = self.shown_docks if shown is None else shown
        while dock_anchor(shown[name]) is not None:
            name = dock_anchor(shown[name])
        return shown[name]

    def _size_edges(self, edges: set[str], again: bool = True, tabs: list[Tab] | None = None) -> None:
        """Command each edge's total width (viser shares it among that edge's columns, see Layout.region_widths), in
        ``tabs`` (None: every open tab).

        Sent through the edge's panel that the browser places last (it places panels in
        creation order, PANELS). The browser drops a width that arrives in the same update as
        a move that merges or adds a column on that edge (its column bookkeeping restores the
        old widths; measured: a re-shown images panel came back 300 px instead of 420), so
        the width is sent once more after RESEND_S, when the moves have been drawn.
        """
        if not edges or self.layout is None:
            return
        for tab in self._open_tabs() if tabs is None else tabs:
            totals, shown = self.placed(tab).region_widths(), tab.shown_docks  # one snapshot: resends run on a timer
            for edge in edges:
                on_edge = [p for p in PANELS if p in shown and self._edge(p, shown) == edge]
                if on_edge:
                    tab.placer.set_width(self.panels[on_edge[-1]], totals[edge])
                elif edge == "left":  # the main panel alone: a share squeezed by a narrow window would stay otherwise
                    tab.placer.set_width(self.gui.main_panel, totals[edge])
        if again:
            with self._timer_lock:
                if self._timer is not None:
                    self._timer.cancel()
                    edges = edges | self._timer.args[0]
                self._timer = threading.Timer(RESEND_S, self._size_edges, (set(edges), False))
                self._timer.daemon = True
                self._timer.start()
            self._resend_late()

    def client_connected(self, client) -> None:
        """Place the layout in a tab that connects, and send the edges' widths again shortly after: the placement
        arrives with its width in one update, which the browser drops (as for a move, see _size_edges), so a tab
        opened after the layout was applied showed the debug layout's left edge 620 px wide instead of 580 (its 3D
        view 307 px)."""
        tab = Tab(placer_for(self.gui, client))
        with self._tabs_lock:
            self.tabs[client.client_id] = tab
        if self.layout is not None:
            self._place_tab(tab, set(PANELS))
            self._size_edges({"left", "right"})

    def client_disconnected(self, client) -> None:
        with self._tabs_lock:
            self.tabs.pop(client.client_id, None)

    def _resend_late(self) -> None:
        """Both edges' current widths sent again at each of LATE_RESEND_S (sending a width the browser already shows
        changes nothing, and each send reads the layout as it is then)."""
        with self._timer_lock:  # a newer change restarts them (a dragged width slider would pile up threads)
            for timer in self._late_timers:
                timer.cancel()
            self._late_timers = [threading.Timer(delay, self._resend_edges) for delay in LATE_RESEND_S]
            for timer in self._late_timers:
                timer.daemon = True
                timer.start()

    def _resend_edges(self) -> None:
        if not self._stopped:
            self._size_edges({"left", "right"}, again=False)

    def stop(self) -> None:
        self._stopped = True
        with self._timer_lock:
            for timer in [self._timer, *self._late_timers]:
                if timer is not None:
                    timer.cancel()

    def _describe(self, shown: dict[str, str]) -> None:
        lines = []
        for tab in sorted(self._open_tabs(), key=lambda t: t.window_px or 0):
            placed = self.placed(tab)
            if placed is not self.layout:
                lines.append(f"- a narrow window ({tab.window_px} px): panels in one column on the right there, "
                             f"{placed.region_widths()['right']} px wide (wider windows get the layout as it is)")
        for name in PANELS:
            place = self.layout.panels[name]
            # Not yet placed (a layout being applied on another thread, the window check's: KeyError in a browser test
            # that switched layouts); the placement that follows describes it.
            if place.visible and name in shown and shown[name] != place.dock:
                anchor = dock_anchor(place.dock)
                why = "is hidden" if not self.layout.panels[anchor].visible else "floats"
                lines.append(f"- {name}: `{place.dock}` but {anchor} {why}, so `{shown[name]}`")
        self.note.content = ("_Shown differently from the layout:_\n" + "\n".join(dict.fromkeys(lines))) if lines else ""

    # ------------------------------------------------------------------ run-time changes
    def set_visible(self, name: str, visible: bool) -> None:
        """Show or hide a panel; panels stacked on it move to its place (or back onto it)."""
        if self.layout is None:
            return
        self.layout.panels[name].visible = bool(visible)
        self.panels[name].visible = bool(visible)
        self.boxes[name].value = bool(visible)
        self._place({name} if visible else set())
        if visible:
            self._on_shown()

    def set_dock(self, name: str, dock: str) -> bool:
        """Dock a panel (left/right/float/above:<panel>/below:<panel>) for every client; a circle of stacks is refused."""
        if self.layout is None:
            return False
        try:
            self.layout = self.layout.with_dock(name, dock)
        except InputError as exc:
            self._notify("layout", str(exc), "red")
            self.docks[name].value = self.layout.panels[name].dock  # the control shows what is in effect
            return False
        self.docks[name].value = dock
        self._place({name})
        return True

    def set_width(self, name: str, width: float) -> bool:
        """Set a panel's width in CSS pixels (0: leave it to the viewer); out-of-range values, as while typing, are ignored."""
        if self.layout is None:
            return False
        try:
            value = check_width(None if width == 0 else width, f"{name} width")
        except InputError as exc:
            self.note.content = f"_{exc}_"
            return False
        self.layout.panels[name].width = value
        self._describe(self.shown_docks)  # the note of a refused width stayed up after a valid one was typed
        if self.layout.panels[name].visible and value is not None:
            if self._edge(name) == "float":
                for tab in self._open_tabs():
                    tab.placer.set_width(self.panels[name], value)
            else:
                self._size_edges({self._edge(name)})
        return True

    def save(self, name: str) -> Path | None:
        """Save the layout as shown now (panels as set here, 3D toggles as ticked) and make it the current one."""
        try:
            base = self.layout or Layout(name)
            layout = Layout(name, base.description, base.dark_mode,
                            {k: dataclasses.replace(v) for k, v in base.panels.items()}, dataclasses.replace(base.scene),
                            base.stage)
            path = save_layout(layout, self.layout_dir)
        except EvposeError as exc:
            self._notify("layout", str(exc), "red")
            return None
        self.dropdown.options = sorted(k for k, v in self.available().items() if isinstance(v, Layout))
        self.dropdown.value = name
        self.layout = Layout.from_dict(layout.to_dict())
        self._notify("layout", f"saved {path}", "green")  # a save said nothing: the button seemed to do nothing
        return path
