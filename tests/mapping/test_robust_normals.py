"""One-sided normals: points next to a crease or a parallel layer get their own surface's normal; clean points are untouched."""

from __future__ import annotations

import numpy as np

from evpose.mapping.normals import estimate_neighbourhoods
from evpose.mapping.robust_normals import robust_normals


def _grid_plane(rng, lo, hi, spacing, noise, axis=2, offset=0.0):
    a = np.arange(lo[0], hi[0], spacing)
    b = np.arange(lo[1], hi[1], spacing)
    aa, bb = np.meshgrid(a, b, indexing="ij")
    p = np.zeros((aa.size, 3))
    free = [d for d in range(3) if d != axis]
    p[:, free[0]] = aa.ravel() + rng.uniform(-0.3, 0.3, aa.size) * spacing
    p[:, free[1]] = bb.ravel() + rng.uniform(-0.3, 0.3, aa.size) * spacing
    p[:, axis] = offset + rng.normal(0.0, noise, aa.size)
    return p


def _refit(points, k=16, min_curvature=0.01, cutoff=0.015):
    nb = estimate_neighbourhoods(points, k)
    n, c = robust_normals(points, nb.indices, nb.normals, nb.curvature, min_curvature, cutoff)
    return nb, n, c


def test_wall_point_behind_a_parallel_layer_keeps_the_wall_normal_and_a_low_curvature():
    # A cabinet's back face 6 cm in front of a wall, 10 cm spacing (100 points/m^2): plain
    # PCA mixes both layers (high curvature), the refit sees one plane.
    rng = np.random.default_rng(0)
    wall = _grid_plane(rng, (0, 0), (2, 2), 0.1, 0.005, axis=0, offset=0.0)
    back = _grid_plane(rng, (0.5, 0.5), (1.5, 1.5), 0.1, 0.005, axis=0, offset=0.06)
    pts = np.concatenate([wall, back])
    nb, n, c = _refit(pts)
    behind = (np.abs(wall[:, 1] - 1.0) < 0.4) & (np.abs(wall[:, 2] - 1.0) < 0.4)
    assert np.median(nb.curvature[:wall.shape[0]][behind]) > 0.05
    assert np.median(c[:wall.shape[0]][behind]) < 0.01
    assert np.mean(np.abs(n[:wall.shape[0]][behind, 0]) > np.cos(np.radians(5.0))) > 0.95


def test_points_next_to_a_crease_get_their_own_face_normal():
    rng = np.random.default_rng(1)
    floor = _grid_plane(rng, (0.0, 0.0), (1.0, 1.0), 0.03, 0.002, axis=2)
    wall = _grid_plane(rng, (0.0, 0.03), (1.0, 1.0), 0.03, 0.002, axis=0)  # x = 0, rising from the floor
    pts = np.concatenate([floor, wall])
    nb, n, _ = _refit(pts)
    near = np.flatnonzero((floor[:, 0] < 0.06) & (floor[:, 0] > 0.01))
    pca_ok = np.abs(nb.normals[near, 2]) > np.cos(np.radians(10.0))
    ok = np.abs(n[near, 2]) > np.cos(np.radians(10.0))
    assert ok.mean() > 0.9
    assert ok.mean() > pca_ok.mean() + 0.2


def test_clean_points_and_the_input_arrays_are_left_unchanged():
    rng = np.random.default_rng(2)
    pts = _grid_plane(rng, (0, 0), (1, 1), 0.03, 0.001)
    nb = estimate_neighbourhoods(pts, 16)
    n0, c0 = nb.normals.copy(), nb.curvature.copy()
    n, c = robust_normals(pts, nb.indices, nb.normals, nb.curvature, 0.01, 0.015)
    clean = nb.curvature <= 0.01
    assert clean.mean() > 0.9
    assert np.array_equal(n[clean], n0[clean]) and np.array_equal(c[clean], c0[clean])
    assert np.array_equal(nb.normals, n0) and np.array_equal(nb.curvature, c0)


def test_refit_is_deterministic():
    rng = np.random.default_rng(3)
    pts = np.concatenate([_grid_plane(rng, (0, 0), (1, 1), 0.05, 0.005),
                          _grid_plane(rng, (0, 0), (1, 1), 0.05, 0.005, axis=2, offset=0.05)])
    a = _refit(pts)
    b = _refit(pts.copy())
    assert np.array_equal(a[1], b[1]) and np.array_equal(a[2], b[2])
