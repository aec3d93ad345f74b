"""Placement sent to one tab (app/tab_placement.py), without a browser (tests/app/test_server_browser.py drives two)."""

from types import SimpleNamespace

import viser

from app.bench import free_port
from app.tab_placement import TabPlacer


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
