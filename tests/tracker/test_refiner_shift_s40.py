"""The painted-edge refiner reading the field where registration does (``map_refinement.fused_registration_shift``):
behind each point's projection, against its image motion, by the lag floor and the point's polarity trail."""

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker.config import TrackerConfig
from evpose.tracker.map_refinement import MapRefinementConfig, PaintedEdgeRefiner

W, H, F = 120, 90, 100.0
K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1.0]])
DOWN = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 2.0], [0, 0, 0, 1.0]])
"""Camera 2 m above the ground looking straight down (image u = world x, 50 px per metre)."""
MOVING = np.array([0.0, 0.0, 0.0, 0.5, 0.0, 0.0])
"""Body twist per second: 0.5 m/s along camera x, so the ground moves left in the image (-25 px/s)."""


def line_field(u_edge: float) -> TemporalDistanceField:
    fld = TemporalDistanceField(DistanceFieldConfig(), W, H)
    img = np.minimum(np.abs(np.arange(W, dtype=np.float64) - u_edge) * 0.25, 1.0).astype(np.float32)
    fld.value[0] = img[None, :]
    fld.grad_u[0] = np.gradient(img)[None, :]
    fld.grad_v[0] = 0.0
    fld.box[:] = (0, H, 0, W)
    return fld


def painted_line(n: int = 20) -> ContourMap:
    pts = np.stack([np.zeros(n), np.linspace(-0.3, 0.3, n), np.zeros(n)], axis=1)
    return ContourMap.from_points(pts, edge_normal=np.tile([1.0, 0.0, 0.0], (n, 1)), plane_normal=np.tile([0.0, 0.0, 1.0], (n, 1)),
                                  brightness_sign=np.ones(n), curvature=np.zeros(n))


def converge(**shift) -> np.ndarray:
    cmap = painted_line()
    refiner = PaintedEdgeRefiner(MapRefinementConfig(gain=0.2), cmap)
    pts = np.array(cmap.points)
    fld = line_field((W - 1) / 2)
    for _ in range(150):
        refiner.update(pts, fld, DOWN, K, None, **shift)
    return refiner.offsets


def test_on_by_default():
    assert TrackerConfig().map_refinement.fused_registration_shift is True


def test_without_a_shift_the_points_stay_on_the_fields_minimum_bit_for_bit():
    plain = converge()
    assert np.allclose(plain, 0.0, atol=0.004)
    assert np.array_equal(converge(twist=MOVING, lag_s=0.0, floor_px=0.0, trail_px=None), plain)
    assert np.array_equal(converge(twist=None, floor_px=0.5), plain)  # no twist: no direction to shift along


def test_a_lag_floor_puts_the_edge_ahead_of_the_trailing_minimum():
    # Registration reads the field 0.5 px behind the projection (to the right, the image moves left): the edge the
    # refiner learns is 0.5 px = 1 cm left of the field's minimum, i.e. where registration's reading finds the minimum.
    off = converge(twist=MOVING, lag_s=0.0, floor_px=0.5)
    assert np.allclose(off, -0.01, atol=0.004)
    assert np.all(off < converge().mean() - 0.006)
    # Moving the other way, the other side.
    assert np.allclose(converge(twist=-MOVING, lag_s=0.0, floor_px=0.5), 0.01, atol=0.004)


def test_a_points_trail_shifts_it_as_the_floor_does():
    n = len(painted_line())
    by_trail = converge(twist=MOVING, lag_s=0.0, floor_px=0.0, trail_px=np.full(n, 0.5))
    assert np.allclose(by_trail, converge(twist=MOVING, lag_s=0.0, floor_px=0.5), atol=1e-9)
