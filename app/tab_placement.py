"""Panel placement sent to one browser tab: each tab gets the layout fitted to its own window.

viser's placement commands (``PanelHandle.dock_right``, ``float``, ``set_width``...) are broadcast: every tab gets
them, and they persist and replay to tabs that connect later. So with several tabs open, the narrow-window form of a
layout (app/window_fit.py) was placed for all of them, fitted to the narrowest (session 27's leftover: a 1000 px tab
beside a 1920 px one squeezed both into one column of panels).

viser 1.1 has no public per-tab placement of the server's panels (a panel made by ``client.gui.add_panel`` is a tab's
own, but then so would be every image and control in it: each frame drawn and sent once per tab). Its placement is,
though, only a message per axis (``GuiSetPanelPositionMessage``, ``GuiSetPanelWidthMessage``) stamped with a
layout counter and a run id that the browser compares before applying it (a later counter wins). :class:`TabPlacer`
sends those messages, stamped by the server's own GUI (so they are ordered with its broadcasts), on one tab's
connection instead of to all. Measured (/tmp/s28/ux28/perclient_probe.py, two tabs 1400 and 800 px): a panel
docked left for the 800 px tab only moved there and stayed on the right in the other. It uses three private names
of viser (``_websock_connection``, ``_next_layout_counter``, ``_layout_run_id``); the browser test of narrow
windows (tests/app/test_server_browser.py) checks the behaviour, so a viser that changes them fails there. A viser
without them (the project accepts any 1.x) gets :class:`BroadcastPlacer` from :func:`placer_for`: every tab placed
alike, as before session 28, rather than an AttributeError on connect.
"""

from __future__ import annotations

import dataclasses

from viser import _messages

class TabPlacer:
    """Placement commands for the server's panels, sent to one tab only."""

    def __init__(self, gui, client):
        self._gui = gui
        """The server's GuiApi: its layout counter and run id stamp the messages."""
        self.client = client

    def _send(self, message) -> None:
        conn = self.client._websock_connection
        if conn.get_message_buffer().done:
            # The tab closed (its disconnect callback, which forgets it, may still be on its way): viser warned
            # "Queued a GuiSetPanelPositionMessage on a closed connection" (session 28's suite).
            return
        stamped = dataclasses.replace(message, counter=self._gui._next_layout_counter(), run_id=self._gui._layout_run_id)
        conn.queue_message(stamped)

    def _position(self, panel, position: dict) -> None:
        self._send(_messages.GuiSetPanelPositionMessage(panel._placement_uuid, position, counter=0, run_id=""))

    def dock_left(self, panel) -> None:
        self._position(panel, {"kind": "edge", "edge": "left"})

    def dock_right(self, panel) -> None:
        self._position(panel, {"kind": "edge", "edge": "right"})

    def dock_beside(self, panel, side: str, anchor) -> None:
        """Stack ``panel`` ``side`` ("above" / "below") the docked panel ``anchor``."""
        self._position(panel, {"kind": "split", "anchor_uuid": anchor._placement_uuid, "side": side})

    def float(self, panel, x: float, y: float, width: float | None) -> None:
        self._position(panel, {"kind": "float", "x": x, "y": y})
        if width is not None:
            self.set_width(panel, width)

    def set_width(self, panel, width: float) -> None:
        self._send(_messages.GuiSetPanelWidthMessage(panel._placement_uuid, float(width), counter=0, run_id=""))


class BroadcastPlacer:
    """The same commands through the panels' public methods: every tab gets them (viser's own behaviour)."""

    def dock_left(self, panel) -> None:
        panel.dock_left()

    def dock_right(self, panel) -> None:
        panel.dock_right()

    def dock_beside(self, panel, side: str, anchor) -> None:
        (panel.dock_above if side == "above" else panel.dock_below)(anchor)

    def float(self, panel, x: float, y: float, width: float | None) -> None:
        panel.float(x=x, y=y, width=width)

    def set_width(self, panel, width: float) -> None:
        panel.set_width(width)


def placer_for(gui, client) -> TabPlacer | BroadcastPlacer:
    """A :class:`TabPlacer` for ``client`` when this viser has the private names it stamps messages with, else a
    :class:`BroadcastPlacer`."""
    private = (hasattr(gui, "_next_layout_counter") and hasattr(gui, "_layout_run_id")
               and hasattr(client, "_websock_connection")
               and all(hasattr(_messages, m) for m in ("GuiSetPanelPositionMessage", "GuiSetPanelWidthMessage")))
    return TabPlacer(gui, client) if private else BroadcastPlacer()
