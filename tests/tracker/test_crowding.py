"""The crowding test: a point is crowded when another edge's point projects within the radius, off its own line."""

import numpy as np

from evpose.tracker.crowding import crowded_points

K = np.array([[200.0, 0.0, 100.0], [0.0, 200.0, 80.0], [0.0, 0.0, 1.0]])
T = np.eye(4)  # camera at the origin looking along +z: a point (x, y, 2) projects to (100 + 100 x, 80 + 100 y)


def _edge(u0, v0, du, dv, n, tangent):
    """n points from pixel (u0, v0) in steps (du, dv) pixels, at 2 m, with a world tangent."""
    k = np.arange(n)
    pts = np.c_[(u0 + k * du - 100.0) / 100.0, (v0 + k * dv - 80.0) / 100.0, np.full(n, 2.0)]
    return pts, np.tile(tangent, (n, 1)).astype(np.float64)


def test_a_lone_edge_is_not_crowded_by_its_own_points():
    pts, tan = _edge(50, 40, 1.0, 0.0, 40, [1.0, 0.0, 0.0])
    assert not crowded_points(pts, tan, T, K, 3.0, 1.0).any()


def test_a_parallel_edge_two_pixels_away_crowds_both_edges():
    a, ta = _edge(50, 40, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    b, tb = _edge(50, 42, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    far, tf = _edge(50, 60, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    out = crowded_points(np.r_[a, b, far], np.r_[ta, tb, tf], T, K, 3.0, 1.0)
    assert out[:40].all() and not out[40:].any()
    assert not crowded_points(np.r_[a, b], np.r_[ta, tb], T, K, 1.5, 1.0).any()  # 2 px is beyond a 1.5 px radius


def test_only_the_points_near_a_corner_are_crowded():
    a, ta = _edge(50, 40, 1.0, 0.0, 30, [1.0, 0.0, 0.0])  # columns 50..79 on row 40
    b, tb = _edge(80, 41, 0.0, 1.0, 30, [0.0, 1.0, 0.0])  # rows 41..70 on column 80
    out = crowded_points(np.r_[a, b], np.r_[ta, tb], T, K, 3.0, 1.0)
    cols = np.arange(50, 80)
    rows = np.arange(41, 71)
    assert np.array_equal(out[:30], np.hypot(cols - 80, 41 - 40) <= 3.0 + 1e-9)
    assert np.array_equal(out[30:], np.hypot(80 - 79, rows - 40) <= 3.0 + 1e-9)


def test_points_without_a_tangent_or_a_radius_are_never_crowded():
    a, ta = _edge(50, 40, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    b, tb = _edge(50, 42, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    out = crowded_points(np.r_[a, b], np.r_[np.zeros_like(ta), tb], T, K, 3.0, 1.0)
    assert not out[:20].any() and out[20:].all()  # the unknown ones still crowd the others
    assert not crowded_points(np.r_[a, b], np.r_[ta, tb], T, K, 0.0, 1.0).any()
    assert crowded_points(np.zeros((0, 3)), np.zeros((0, 3)), T, K, 3.0, 1.0).shape == (0,)


def test_a_radius_near_zero_or_projections_far_off_the_image_do_not_blow_up_the_grid():
    a, ta = _edge(50, 40, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    b, tb = _edge(50, 42, 1.0, 0.0, 20, [1.0, 0.0, 0.0])
    # 1e-9 px once asked for ~1e21 cells ("array is too big"); now nothing is within such a radius.
    assert not crowded_points(np.r_[a, b], np.r_[ta, tb], T, K, 1e-9, 1.0).any()
    far, tf = _edge(5e7, 40, 1.0, 0.0, 3, [1.0, 0.0, 0.0])  # projected 5e7 px away: a spread of 5e7 px
    out = crowded_points(np.r_[a, b, far], np.r_[ta, tb, tf], T, K, 3.0, 1.0)
    assert out[:40].all() and not out[40:].any()
