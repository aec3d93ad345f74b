"""Every control of the viewer's own panels has hover text saying what it does (the view has no manual beside it)."""

import socket

from app.server import AppConfig, ViewerApp


def test_every_control_has_hover_text(tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    (tmp_path / "data").mkdir()
    app = ViewerApp(AppConfig(data=[tmp_path / "data"], port=port, layout_dir=tmp_path / "layouts",
                              export_dir=tmp_path / "exports"))
    try:
        handles = app.gui._gui_input_handle_from_uuid.values()  # viser keeps no public list of them
        without = sorted(h._impl.props.label for h in handles if not getattr(h._impl.props, "hint", None))
        assert len(handles) > 40 and without == []  # "save current layout" had none (session 29)
    finally:
        app.stop()
