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
