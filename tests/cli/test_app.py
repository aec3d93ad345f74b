"""``evpose app``: command-line options reach the viewer's configuration."""

from __future__ import annotations

from pathlib import Path

import pytest


class _Started(Exception):
    pass


def _capture_config(monkeypatch) -> dict:
    import app.server

    seen: dict = {}

    def fake_viewer(cfg):
        seen["cfg"] = cfg
        raise _Started  # stop before the command's serve-forever loop

    monkeypatch.setattr(app.server, "ViewerApp", fake_viewer)
    return seen


def test_cache_dir_and_no_disk_cache_reach_the_viewer(monkeypatch, tmp_path: Path):
    from evpose.cli.main import run

    seen = _capture_config(monkeypatch)
    with pytest.raises(_Started):
        run(["app", "--cache-dir", str(tmp_path / "c"), "--no-disk-cache", "--port", "0"])
    assert seen["cfg"].disk_cache.directory == tmp_path / "c"
    assert seen["cfg"].disk_cache.enabled is False


def test_disk_cache_is_on_by_default(monkeypatch):
    from evpose.cli.main import run

    seen = _capture_config(monkeypatch)
    with pytest.raises(_Started):
        run(["app", "--port", "0"])
    assert seen["cfg"].disk_cache.enabled is True and seen["cfg"].disk_cache.directory is None


@pytest.mark.parametrize("args, message", [
    (["--data", "no/such/folder"], "no/such/folder: no such folder"),
    (["--data", "README.md"], "README.md: not a folder"),
    (["--layout", "nope"], "--layout 'nope' is not in"),
    (["--port", "99999"], "--port must be 0..65535, got 99999"),
    (["--export-dir", "README.md"], "README.md: output folder exists and is a file"),
])
def test_bad_arguments_are_one_line_errors_before_the_server_starts(monkeypatch, capsys, args, message):
    # A typo in --data served an empty browser, an unknown layout a default one, a port > 65535 a bind() traceback.
    from evpose.cli.main import run

    started = _capture_config(monkeypatch)
    assert run(["app", "--data", "demo_data", "--port", "0", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not started


def test_the_default_data_folders_are_the_bundled_ones_when_started_elsewhere(monkeypatch, tmp_path: Path):
    # Run from a folder without demo_data/ and maps/, the default --data used to be refused as missing.
    from evpose.cli.main import run

    repo = Path(__file__).resolve().parents[2]
    monkeypatch.chdir(tmp_path)
    seen = _capture_config(monkeypatch)
    with pytest.raises(_Started):
        run(["app", "--port", "0"])
    assert seen["cfg"].data == [repo / "demo_data", repo / "maps"]


def test_the_default_data_folders_of_the_current_folder_come_first(monkeypatch, tmp_path: Path):
    from evpose.cli.main import run

    (tmp_path / "demo_data").mkdir()
    (tmp_path / "maps").mkdir()
    monkeypatch.chdir(tmp_path)
    seen = _capture_config(monkeypatch)
    with pytest.raises(_Started):
        run(["app", "--port", "0"])
    assert seen["cfg"].data == [Path("demo_data"), Path("maps")]


@pytest.mark.parametrize("how", ["ctrl-c to the process group", "sigterm to the server"])
def test_the_viewer_and_its_warm_up_stop_without_a_traceback(tmp_path: Path, how: str):
    import os
    import signal
    import socket
    import subprocess
    import sys
    import time

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    root = Path(__file__).resolve().parents[2]
    proc = subprocess.Popen([sys.executable, "-m", "evpose.cli.main", "app", "--port", str(port), "--cache-dir", str(tmp_path / "cache")],
                            cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            # as from a terminal: a harness run in the background (or under time(1)) ignores SIGINT,
                            # and the child would inherit that
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        for line in proc.stdout:  # viser's banner, then ours once the server and its warm-up process are up
            if "evpose app: serving" in line:
                break
        else:
            raise AssertionError(f"the viewer did not start: {proc.stderr.read()}")
        time.sleep(2.0)  # the warm-up process is preparing a demo recording now
        if how.startswith("ctrl-c"):
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert "Traceback" not in err and "leaked" not in err, err
    assert "interrupted" in err
    deadline = time.monotonic() + 10.0  # multiprocessing's resource tracker exits just after the server
    while time.monotonic() < deadline:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        raise AssertionError("a process of the viewer's group (the warm-up?) was left running")


@pytest.mark.parametrize("text, message", [
    ('{"name": "mine", "panels": [', "mine.json: line 1: not valid JSON"),
    ('{"name": "mine", "bogus": 1}', "mine.json: bogus: unknown key"),
])
def test_a_broken_saved_layout_is_a_one_line_error_before_the_server_starts(monkeypatch, capsys, tmp_path, text, message):
    import app.layouts
    from evpose.cli.main import run

    (tmp_path / "mine.json").write_text(text)
    monkeypatch.setattr(app.layouts, "LAYOUT_DIR", tmp_path)
    started = _capture_config(monkeypatch)
    assert run(["app", "--data", "demo_data", "--port", "0", "--layout", "mine"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not started


def test_bookmarks_reach_the_viewer_and_an_unreadable_file_is_a_one_line_warning_not_an_error(monkeypatch, capsys, tmp_path):
    from evpose.cli.main import run

    seen = _capture_config(monkeypatch)
    path = tmp_path / "lesson.json"
    path.write_text('{"bookmarks": [')
    with pytest.raises(_Started):
        run(["app", "--data", "demo_data", "--port", "0", "--bookmarks", str(path)])
    assert seen["cfg"].bookmarks_path() == path
    err = capsys.readouterr().err.strip()
    assert err == f"evpose app: warning: bookmarks not read: {path}: line 1: not valid JSON (Expecting value)"
    assert path.read_text() == '{"bookmarks": ['
