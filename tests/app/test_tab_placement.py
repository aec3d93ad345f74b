"""Placement sent to one tab (app/tab_placement.py), without a browser (tests/app/test_server_browser.py drives two)."""

from types import SimpleNamespace

import viser

from app.bench import free_port
from app.tab_placement import BroadcastPlacer, TabPlacer, placer_for


def test_placement_goes_to_one_tab_stamped_by_the_server_and_never_to_a_closed_one():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        panel = server.gui.add_panel()
        sent, buffer = [], SimpleNamespace(done=False)
        conn = SimpleNamespace(queue_message=sent.append, get_message_buffer=lambda: buffer)
        tab = TabPlacer(server.gui, SimpleNamespace(_websock_connection=conn))
        tab.dock_right(panel)
        tab.set_width(panel, 300)
        assert [type(m).__name__ for m in sent] == ["GuiSetPanelPositionMessage", "GuiSetPanelWidthMessage"]
        # Ordered with the server's own broadcasts: its counter, its run id.
        assert sent[1].counter > sent[0].counter and sent[0].run_id == server.gui._layout_run_id
        buffer.done = True  # the tab closed: viser warned of a message queued on a closed connection
        tab.dock_left(panel)
        assert len(sent) == 2
    finally:
        server.stop()


def test_a_viser_without_the_private_names_gets_every_tab_placed_alike_instead_of_an_error():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        conn = SimpleNamespace(queue_message=lambda m: None, get_message_buffer=lambda: SimpleNamespace(done=False))
        assert isinstance(placer_for(server.gui, SimpleNamespace(_websock_connection=conn)), TabPlacer)
        placer = placer_for(server.gui, SimpleNamespace())  # a client object without _websock_connection
        assert isinstance(placer, BroadcastPlacer)
        calls = []
        panel = SimpleNamespace(dock_left=lambda: calls.append("left"), dock_below=lambda a: calls.append(("below", a)),
                                float=lambda **kw: calls.append(("float", kw)), set_width=lambda w: calls.append(("width", w)))
        placer.dock_left(panel)
        placer.dock_beside(panel, "below", "anchor")
        placer.float(panel, 10.0, 20.0, None)
        placer.set_width(panel, 300)
        assert calls == ["left", ("below", "anchor"), ("float", {"x": 10.0, "y": 20.0, "width": None}), ("width", 300)]
    finally:
        server.stop()
