"""``evpose`` entry point: Ctrl+C at any moment is one line and exit 130."""

import importlib

from evpose.cli import main as cli_main


def test_ctrl_c_while_the_command_imports_is_one_line_not_a_traceback(monkeypatch, capsys):
    def interrupted_import(name, *args):
        raise KeyboardInterrupt  # numba/gtsam/open3d take about a second to import: a Ctrl+C lands there

    monkeypatch.setattr(importlib, "import_module", interrupted_import)
    assert cli_main.run(["convert", "in", "out.h5"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["evpose convert: interrupted"]
