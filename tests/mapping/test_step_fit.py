"""Step fits: a straight albedo edge recovered from sparse noisy points; noise does not look like an edge."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.step_fit import fit_step_lines, local_steps, side_contrast


def _edge_points(seed, density=400.0, step=0.5, noise=0.03):
    rng = np.random.default_rng(seed)
    n = int(4 * density)
    pts = rng.random((n, 2)) * 2.0
    inten = np.where(pts[:, 0] > 1.0, 0.2 + step, 0.2) + rng.normal(0.0, noise, n)
    return pts, inten


def test_straight_edge_is_recovered_from_an_offset_tilted_chain():
    errors = []
    for seed in range(5):
        pts, inten = _edge_points(seed)
        y = np.arange(0.5, 1.5, 0.01)
        chain = np.stack([1.03 + 0.03 * (y - 1.0), y], axis=1)
        normals = np.tile([1.0, 0.0], (y.size, 1))
        spacing = 0.47 / np.sqrt(400.0)
        p, n, fitted = fit_step_lines(chain, normals, pts, inten, cKDTree(pts), eps=2 * spacing, min_points=18,
                                      half_across=2.5 * spacing, width=0.5 * spacing)
        assert fitted.all()
        assert np.all(n[:, 0] > 0.99)  # still dark -> bright
        errors.append(np.abs(p[:, 0] - 1.0).max())
    assert np.median(errors) < 0.01 and max(errors) < 0.03


def test_side_contrast_separates_an_edge_from_noise():
    pts, inten = _edge_points(1)
    y = np.arange(0.3, 1.7, 0.01)
    normals = np.tile([1.0, 0.0], (y.size, 1))
    tree = cKDTree(pts)
    on_edge = np.stack([np.full(y.size, 1.0), y], axis=1)
    step, t = side_contrast(on_edge, normals, pts, inten, tree, 0.06, 0.005)
    assert abs(step - 0.5) < 0.05 and t > 20
    off_edge = np.stack([np.full(y.size, 1.5), y], axis=1)  # inside the bright half: no edge
    step, t = side_contrast(off_edge, normals, pts, inten, tree, 0.06, 0.005)
    assert abs(step) < 0.03 and abs(t) < 6


def test_local_steps_drop_where_a_chain_leaves_the_edge():
    pts, inten = _edge_points(2)
    y = np.arange(0.2, 1.8, 0.01)
    x = np.where(y < 1.0, 1.0, 1.6)  # on the edge, then 60 cm into the bright side
    chain = np.stack([x, y], axis=1)
    normals = np.tile([1.0, 0.0], (y.size, 1))
    local = local_steps(chain, normals, pts, inten, cKDTree(pts), 0.06, 0.005, 8)
    assert np.nanmedian(local[y < 0.9]) > 0.4
    assert np.nanmedian(local[y > 1.1]) < 0.05



def test_sparse_edge_line_uses_the_points_near_the_ends_of_its_run():
    # A sparse scan (10 cm rows): along most of the run the nearest dark and bright points are
    # 14 cm apart (gap middle 2 cm off the edge); only near the run's two ends do a dark and a
    # bright point sit 1 cm either side of it. Those pin the line - a band trimmed at the
    # run's ends would miss them and leave the edge centimetres off.
    rows = np.arange(0.4, 1.6001, 0.1)
    dark = [(x, y) for y in rows for x in (0.95, 0.85, 0.75)]
    bright = [(x, y) for y in rows for x in (1.09, 1.19, 1.29)]
    for y in (0.42, 1.58):
        dark.append((0.99, y))
        bright.append((1.01, y))
    pts = np.array(dark + bright, np.float64)
    inten = np.r_[np.full(len(dark), 0.2), np.full(len(bright), 0.65)]
    y = np.arange(0.4, 1.6001, 0.01)
    chain = np.stack([np.full(y.size, 1.02), y], axis=1)
    normals = np.tile([1.0, 0.0], (y.size, 1))
    spacing = 0.047  # the whole cloud's spacing: this region is sparser than most of the scan
    p, n, fitted = fit_step_lines(chain, normals, pts, inten, cKDTree(pts), eps=2 * spacing, min_points=18,
                                  half_across=2.5 * spacing, width=0.5 * spacing)
    assert fitted.all() and np.all(n[:, 0] > 0.99)
    assert np.abs(p[:, 0] - 1.0).max() < 0.01
