"""Empty arguments and output paths under folders nothing can be created in fail in one line, before any work
(session 32 left both: ``bench --out ""`` wrote into the current folder, ``bench --out /proc/x`` as root failed after
40 s)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from evpose.cli.main import run


@pytest.mark.parametrize("argv, flag", [
    (["bench", "--suite", "quick", "--workers", "0", "--no-progress", "--out", ""], "--out"),
    (["bench", "--suite", "quick", "--workers", "0", "--no-progress", "--out="], "--out"),
    (["track", "", "--map", "m.ply", "--out", "e.txt"], "argument 1"),
    (["eval", "e.txt", "r.h5", "--json", " "], "--json"),
])
def test_an_empty_argument_is_refused_and_nothing_is_written(tmp_path, monkeypatch, capsys, argv, flag):
    monkeypatch.chdir(tmp_path)
    assert run(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{flag}: empty value" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs a /proc file system")
def test_an_output_under_proc_is_refused_before_the_benchmark_starts(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert run(["bench", "--suite", "quick", "--workers", "0", "--no-progress", "--out", "/proc/evpose-out"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith("evpose bench: error: /proc/evpose-out: ")
    assert list(tmp_path.iterdir()) == []


def test_the_writability_probe_leaves_nothing_behind(tmp_path):
    from evpose.io.atomic import check_outputs

    check_outputs([tmp_path / "a" / "b.txt"], folders=[tmp_path / "out"])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(os.geteuid() != 0, reason="access() only says yes to /proc for root")
def test_a_folder_access_allows_but_no_entry_can_be_made_in_is_refused_for_root(tmp_path):
    from evpose.errors import OutputError
    from evpose.io.atomic import check_outputs

    with pytest.raises(OutputError, match="cannot create anything in /proc"):
        check_outputs([Path("/proc/evpose-x.txt")])
