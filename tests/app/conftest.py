"""Fixtures of the viewer tests (the recordings come from app_scenes.py)."""

from __future__ import annotations

import os

import pytest

from app_scenes import map_scene, sweeping_bar_recording


@pytest.fixture(autouse=True, scope="session")
def _private_viewer_cache(tmp_path_factory):
    """Viewers made by tests (module-scoped ones too) keep their disk cache in a temporary folder, never ~/.cache."""
    old = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("xdg_cache"))
    yield
    if old is None:
        os.environ.pop("XDG_CACHE_HOME", None)
    else:
        os.environ["XDG_CACHE_HOME"] = old


@pytest.fixture
def bar_recording():
    return sweeping_bar_recording()


@pytest.fixture(scope="session")
def squares_scene():
    return map_scene()


@pytest.fixture
def pair_files(tmp_path):
    """Stand-ins for the recording and map files the key is made of (the engine gets the scene in memory)."""
    rec, cmap = tmp_path / "rec.h5", tmp_path / "map.ply"
    rec.write_bytes(b"recording bytes")
    cmap.write_bytes(b"map bytes")
    return rec, cmap


@pytest.fixture(scope="module")
def page(viewer):
    """A headless Chromium page on the test module's own ``viewer`` fixture (the browser tests)."""
    from browser_session import viewer_page  # Playwright only where a test asks for a page

    with viewer_page(viewer) as pg:
        yield pg
