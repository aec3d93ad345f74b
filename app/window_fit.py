"""Layouts in windows narrower than they are made for: the panels go into one column on the right, narrower.

The shipped layouts are made for NARROW_WINDOW_PX (1280 px) and wider. Below that viser squeezed every column in
proportion and the 3D view down to its 121 px minimum (session 26, a5: debug at 1000 px: 3D view 121 px; at 700 px the
main panel 185 px wide with its dropdowns and buttons cut off). The server learns each tab's window width from the
3D view's width the tab reports with its camera (``client.camera.image_width``) plus the edges it was told to draw;
when the layout would leave the view less than FIT_BELOW_VIEW_PX there, the layout is *placed* as :func:`fitted` makes it
(the layout itself, and what "save" writes, stay as chosen):

- the main panel keeps its own column on the left (its controls are never squeezed under CONTROL_PANEL_PX);
- every other shown panel (left or right, not floating) joins one column on the right, in the order right-edge
  panels first, then left-edge ones (parameters below images and plots in the debug layout), each edge's stacks top
  to bottom as the layout has them (teaching: "How it works" above the images; session 28);
- that column is as wide as the layout's widest right-edge column, but no wider than what leaves the view
  MIN_VIEW_PX, and no narrower than NARROW_COLUMN_PX.

Measured (/tmp/s27/ui27/a5b.py, demo data, headless Chromium): debug at 1000 px: 3D view 121 -> 360 px, nothing cut
off; at 800 px: view 320 px, right column 160 px; at 700 px: view 220 px. A phone-width window (under viser's 576 px
breakpoint) gets viser's mobile view: the 3D view with the main panel as a sheet below it (play, step, time, recording
all reachable); the other panels are not shown there by viser, whatever the layout.

Each tab is fitted to its own window (app/tab_placement.py; until session 27 the narrowest tab's fit was placed in
every tab: viser's placement commands are broadcasts).
"""

from __future__ import annotations

import threading
import time

from app.layouts import CONTROL_PANEL_PX, DEFAULT_COLUMN_PX, MIN_VIEW_PX, PANELS, Layout

FIT_BELOW_VIEW_PX = 240
"""A layout is fitted when it would leave the 3D view narrower than this, CSS px. Not MIN_VIEW_PX (360, what the
shipped layouts leave at 1280 px): a layout saved with wide panels on purpose (images at 500 px on the left: a 320 px
view at 1400 px) is placed as it is; debug at 1000 px (80 px left, viser's minimum 121) and compare (220) are fitted."""
NARROW_COLUMN_PX = 260
"""Narrowest the fitted column gets, CSS px: at MIN_WIDTH (160 px) the parameters' rows and the plots were cut off and
scrolled sideways inside their panels (a5b.py at 800 px); below about 940 px the 3D view gives way instead."""
CLAMPED_VIEW_PX = 130
"""A 3D view this narrow or narrower may be viser's minimum (121 px): the window is then narrower than the view plus
the edges commanded, and the estimate from it is only an upper bound (the next report, after a refit, is exact)."""


def window_width(view_px: int, layout: Layout) -> int:
    """A tab's window width from the 3D view width it reports and the edges ``layout`` (as placed) commands, CSS px."""
    widths = layout.region_widths()
    return int(view_px) + widths["left"] + widths["right"]


SLACK_PX = 24
"""Hysteresis of the fit, CSS px: a layout is fitted once its view would be SLACK_PX under FIT_BELOW_VIEW_PX, and
placed as it is again once its view would be SLACK_PX over. The window estimate is a few px off (viser's column borders: the
debug layout's edges drew 589 + 344 px for 580 + 340 commanded), and with the threshold at MIN_VIEW_PX the debug layout
at 1280 px flipped between the two placements every second without it (a5d.py)."""
JITTER_PX = 16
"""Window width changes smaller than this are not acted on, CSS px (the estimate moves by a few px as columns redraw)."""


def fitted(layout: Layout, window_px: int | None, slack_px: int = 0) -> Layout:
    """``layout`` as placed in a window ``window_px`` wide (None: unknown, as it is); it is fitted when its 3D view
    would be narrower than FIT_BELOW_VIEW_PX - ``slack_px`` there."""
    if window_px is None or layout.view_width(window_px) >= FIT_BELOW_VIEW_PX - slack_px:
        return layout
    shown = dict(layout.placements())

    def stack(name: str) -> list[str]:
        """``name`` and the panels stacked on it, top to bottom as on screen."""
        above = [q for p in shown if shown[p] == f"above:{name}" for q in stack(p)]
        return above + [name] + [q for p in shown if shown[p] == f"below:{name}" for q in stack(p)]

    # Top to bottom as in the layout: the teaching layout's "How it works" (above the images) came below them.
    right = [q for p, dock in shown.items() if dock == "right" for q in stack(p)]
    column = right + [q for p, dock in shown.items() if dock == "left" for q in stack(p)]
    if not column:
        return layout
    wanted = max([layout.panels[p].width or DEFAULT_COLUMN_PX for p in right] or [DEFAULT_COLUMN_PX])
    width = max(NARROW_COLUMN_PX, min(wanted, window_px - CONTROL_PANEL_PX - MIN_VIEW_PX))
    data = layout.to_dict()
    for i, name in enumerate(column):
        data["panels"][name]["dock"] = "right" if i == 0 else f"below:{column[i - 1]}"
        data["panels"][name]["width"] = width if i == 0 else None
    for name in PANELS:  # hidden panels stacked on a moved one would drag it along when shown: they float meanwhile
        if name not in shown and ":" in data["panels"][name]["dock"]:
            data["panels"][name]["dock"] = "float"
    return Layout.from_dict(data, "fitted layout")


CHECK_DELAY_S = 0.5
"""Wait after a tab reports its 3D view's width before fitting, seconds (a drag of the window edge reports many)."""
RECHECK_S = 1.2
"""Fit again this long after a refit, seconds: a report sent before the tab drew the new widths misjudges its window."""


class WindowWatch:
    """Fits the layout's placement to each open tab's window (see the module docstring)."""

    def __init__(self, server, layout_gui):
        self._server = server
        self._layout_gui = layout_gui
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._stopped = False
        self._refit_at = -1e9

    def watch(self, client) -> None:
        """Follow a newly connected tab's reports (its 3D view's width comes with each camera update)."""
        client.camera.on_update(lambda _camera: self._reported())
        self.check_soon()

    def _reported(self) -> None:
        # Reports within RECHECK_S of a refit may predate the new widths (a 3D view still at 121 px read as an 840 px
        # window, a5d.py): the recheck then scheduled reads the reports as they are by then.
        if time.monotonic() - self._refit_at >= RECHECK_S:
            self.check_soon()

    def check_soon(self, delay: float = CHECK_DELAY_S) -> None:
        """Fit once ``delay`` from now; a check already due stays (camera reports come at the frame rate while the
        camera follows the pose: restarting the wait at each would put the check off for as long as that lasts)."""
        with self._lock:
            if self._stopped or (self._timer is not None and self._timer.is_alive()):
                return
            self._timer = threading.Timer(delay, self.check)
            self._timer.daemon = True
            self._timer.start()

    def window_px(self, client) -> int | None:
        """The tab ``client``'s window width, CSS px (None: it has not reported yet)."""
        tab = self._layout_gui.tabs.get(client.client_id)
        if self._layout_gui.layout is None or tab is None or client.camera.image_width <= 0:
            return None
        return window_width(client.camera.image_width, self._layout_gui.placed(tab))

    def check(self) -> None:
        with self._lock:
            self._timer = None  # reports from now on schedule the next check (and the recheck below can)
        refit = False
        for client in list(self._server.get_clients().values()):
            px = self.window_px(client)
            refit |= px is not None and self._layout_gui.set_window_width(client.client_id, px)
        if refit:
            self._refit_at = time.monotonic()
            self.check_soon(RECHECK_S)

    def stop(self) -> None:
        with self._lock:
            self._stopped = True
            if self._timer is not None:
                self._timer.cancel()
