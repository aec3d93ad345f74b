"""Synthetic scans and their maps, built once per session (each build takes ~1-2 s)."""

from __future__ import annotations

import pytest

from evpose.mapping import MapBuildConfig, build_contour_map
from evpose.mapping.synthetic import boxes_on_ground, wall_with_window


@pytest.fixture(scope="session")
def boxes_scan():
    """Three boxes (one dark, two yawed) on a 6 x 6 m ground, 2500 points/m^2, 5 mm range noise."""
    return boxes_on_ground(noise_m=0.005, seed=1)


@pytest.fixture(scope="session")
def boxes_map(boxes_scan):
    return build_contour_map(boxes_scan.points, intensity=boxes_scan.intensity, config=MapBuildConfig())


@pytest.fixture(scope="session")
def window_scan():
    """One 4 x 3 m wall with a 1 x 0.8 m window, 2500 points/m^2, 5 mm range noise."""
    return wall_with_window(noise_m=0.005, seed=2)
