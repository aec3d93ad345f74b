"""Tracing one region: outward normals, refinement to the points, straightening, rim and hole rules."""

from __future__ import annotations

import numpy as np

from evpose.mapping.contours import straighten, trace_region


def _square(rng, n=4000, side=1.0):
    return rng.random((n, 2)) * side


def test_outer_contour_lies_on_the_square_border_with_outward_normals():
    rng = np.random.default_rng(0)
    own = _square(rng)
    # Another surface all around (e.g. walls going down from a table top).
    t = np.linspace(0, 1, 400)
    ring = np.vstack([np.column_stack([t, np.zeros_like(t)]), np.column_stack([t, np.ones_like(t)]),
                      np.column_stack([np.zeros_like(t), t]), np.column_stack([np.ones_like(t), t])])
    rc = trace_region(own, ring, ring, cell=0.02, close_cells=2, min_hole_m2=0.01, spacing=0.01, adjacent_m=0.05)
    assert rc.keep.all() and rc.points2d.shape[0] > 350
    border = np.minimum.reduce([rc.points2d[:, 0], 1 - rc.points2d[:, 0], rc.points2d[:, 1], 1 - rc.points2d[:, 1]])
    assert np.mean(np.abs(border) < 0.01) > 0.9
    away = rc.points2d - 0.5
    assert np.mean(np.einsum("nd,nd->n", away, rc.normals2d) > 0) > 0.99


def test_boundary_with_no_other_surface_is_marked_as_rim():
    rng = np.random.default_rng(1)
    rc = trace_region(_square(rng), np.zeros((0, 2)), np.zeros((0, 2)), 0.02, 2, 0.01, 0.01, 0.05)
    assert rc.points2d.shape[0] > 0 and not rc.keep.any()


def test_see_through_hole_is_kept_and_its_normals_point_into_the_hole():
    rng = np.random.default_rng(2)
    own = _square(rng, 8000)
    hole = np.all(np.abs(own - 0.5) < 0.2, axis=1)
    rc = trace_region(own[~hole], np.zeros((0, 2)), np.zeros((0, 2)), 0.02, 2, 0.01, 0.01, 0.05)
    kept = rc.points2d[rc.keep]
    assert kept.shape[0] > 100
    assert np.all(np.abs(kept - 0.5).max(axis=1) < 0.25)  # only the hole border survives
    towards_centre = np.einsum("nd,nd->n", 0.5 - kept, rc.normals2d[rc.keep])
    assert np.mean(towards_centre > 0) > 0.99


def test_small_sampling_gaps_are_filled_not_traced():
    rng = np.random.default_rng(3)
    own = _square(rng, 8000)
    gap = np.linalg.norm(own - 0.5, axis=1) < 0.03
    rc = trace_region(own[~gap], np.zeros((0, 2)), np.zeros((0, 2)), 0.02, 2, 0.01, 0.01, 0.05)
    assert not np.any(np.linalg.norm(rc.points2d - 0.5, axis=1) < 0.2)


def test_straighten_puts_a_noisy_straight_run_on_one_line():
    rng = np.random.default_rng(4)
    x = np.linspace(0, 1, 200, endpoint=False)
    loop = np.vstack([np.column_stack([x, np.zeros_like(x)]), np.column_stack([np.ones_like(x), x]),
                      np.column_stack([1 - x, np.ones_like(x)]), np.column_stack([np.zeros_like(x), 1 - x])])
    noisy = loop + rng.normal(0, 0.005, loop.shape)
    normals = np.zeros_like(loop)
    normals[:200, 1] = -1
    normals[200:400, 0] = 1
    normals[400:600, 1] = 1
    normals[600:, 0] = -1
    p, n = straighten(noisy, normals, eps=0.03, min_points=20, inlier=0.02)
    mid = np.abs(loop - 0.5).max(axis=1) > 0.45
    err = np.minimum.reduce([np.abs(p[:, 0]), np.abs(1 - p[:, 0]), np.abs(p[:, 1]), np.abs(1 - p[:, 1])])
    assert np.median(err[mid]) < 0.002
    assert np.mean(np.einsum("nd,nd->n", n, normals) > 0.99) > 0.9


def test_straighten_open_chain_fits_each_straight_run_and_keeps_the_ends():
    from evpose.mapping.contours import straighten

    rng = np.random.default_rng(3)
    # An L: 1 m along x, then 0.6 m along y, 1 cm spacing, 4 mm scatter across each leg.
    a = np.stack([np.arange(0.0, 1.0, 0.01), rng.normal(0, 0.004, 100)], axis=1)
    b = np.stack([1.0 + rng.normal(0, 0.004, 60), np.arange(0.0, 0.6, 0.01)], axis=1)
    p = np.concatenate([a, b])
    normals = np.concatenate([np.tile([0.0, -1.0], (100, 1)), np.tile([1.0, 0.0], (60, 1))])
    out, n = straighten(p, normals, eps=0.03, min_points=10, inlier=0.01, closed=False)
    assert np.abs(out[5:90, 1]).max() < 0.004  # the x leg lies on y ~ 0
    assert np.abs(out[110:155, 0] - 1.0).max() < 0.004
    assert np.allclose(n[10:90], [0.0, -1.0], atol=0.02) and np.allclose(n[110:150], [1.0, 0.0], atol=0.02)
