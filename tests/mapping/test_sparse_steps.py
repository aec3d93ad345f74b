"""A low, wide step (a 15 cm landing pad) on a sparse scan: its rim and foot contours lie on the true edges."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.mapping import MapBuildConfig, MapBuildError, build_contour_map
from evpose.mapping.edge_metrics import point_segment_distances
from evpose.mapping.synthetic import Box, boxes_on_ground

# The options this file checks, all off: what the builder did before them.
_OFF = MapBuildConfig(step_min_points=3, step_retry_radius_cells=2.0, contour_min_width=0.0, step_lines=False)


def _misplaced_share(cmap, edges) -> float:
    d = point_segment_distances(cmap.points, edges)
    return float(np.mean(d > 0.02))


@pytest.mark.parametrize("seed", [0, 1])
def test_pad_rim_and_foot_are_placed_on_the_step_face_on_a_sparse_scan(seed):
    # 100 points/m^2: the pad's 15 cm sides hold one to three points per 10 cm, too few within
    # 2 raster cells for the old 3-point rule, so the rim stayed on the top's last points (3-10 cm in).
    scan = boxes_on_ground((Box((0.0, 0.0), (3.0, 3.0, 0.15)),), half_extent=4.0, density=100.0, seed=seed)
    before = _misplaced_share(build_contour_map(scan.points, config=_OFF), scan.edges)
    after = _misplaced_share(build_contour_map(scan.points), scan.edges)
    assert before > 0.2  # measured 0.36 / 0.24
    assert after < 0.06  # measured 0.040 / 0.038


def test_a_region_three_points_wide_gives_no_contour_of_its_own():
    # A 2 m x 6 cm strip tilted 45 deg above a ground grid: a region three points wide, like a
    # 15 cm step's side on a sparse scan. Its outline is all the map would hold; with
    # contour_min_width it holds nothing, so the builder reports no contour.
    rng = np.random.default_rng(0)
    g = np.arange(-1.5, 1.5, 0.05)
    gx, gy = np.meshgrid(g, g)
    ground = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
    sx, ss = np.meshgrid(np.arange(-1.0, 1.0, 0.03), np.array([0.0, 0.03, 0.06]))
    strip = np.c_[sx.ravel(), 0.3 + ss.ravel() / np.sqrt(2), 0.2 + ss.ravel() / np.sqrt(2)]
    pts = np.r_[ground, strip] + 0.001 * rng.standard_normal((ground.shape[0] + strip.shape[0], 3))
    kept = build_contour_map(pts, config=MapBuildConfig(contour_min_width=0.0))
    assert kept.points.shape[0] > 100  # all the strip's: the ground's border is the scan's rim
    with pytest.raises(MapBuildError):
        build_contour_map(pts)
