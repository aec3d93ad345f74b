"""Fixtures of the viewer tests (the recordings come from app_scenes.py)."""

from __future__ import annotations

import pytest

from app_scenes import map_scene, sweeping_bar_recording


@pytest.fixture
def bar_recording():
    return sweeping_bar_recording()


@pytest.fixture(scope="session")
def squares_scene():
    return map_scene()
