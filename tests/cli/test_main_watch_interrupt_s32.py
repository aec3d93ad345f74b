"""An interrupt while the CLI arms its watchdog (which imports numba: a second or more) is the usual one line."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("raised, code, word", [("int", 130, "interrupted"), ("term", 143, "terminated")])
def test_an_interrupt_while_arming_the_watchdog_prints_one_line(monkeypatch, capsys, tmp_path, raised, code, word):
    # Session 32: _watch ran before run()'s try, so a SIGTERM landing in numba's import printed a 20-line traceback.
    import evpose.cli.main as cli_main

    def interrupted(name):
        raise cli_main._Terminated() if raised == "term" else KeyboardInterrupt()

    monkeypatch.setattr(cli_main, "_watch", interrupted)
    rc = cli_main.run(["track", str(tmp_path / "r.h5"), "--map", str(tmp_path / "m.ply"), "--out", str(tmp_path / "e.txt")],
                      watchdog=True)
    assert rc == code
    assert capsys.readouterr().err == f"evpose track: {word}\n"
    assert not (tmp_path / "e.txt").exists()
