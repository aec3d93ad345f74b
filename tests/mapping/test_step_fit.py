"""Step fits: a straight albedo edge recovered from sparse noisy points; noise does not look like an edge."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.step_fit import dominant_axis, fit_step_lines, local_steps, side_contrast


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


def test_sparse_edge_square_to_the_outline_is_fitted_square_with_its_offset_only():
    # 100 points/m^2 (10 cm apart), a tilted chain: free, the line's tilt rests on the few points
    # near its ends (measured max error 2.5 cm, median of 8 seeds); square to the outline, 0.5 cm.
    free, square = [], []
    for seed in range(8):
        rng = np.random.default_rng(seed)
        pts = rng.random((400, 2)) * 2.0
        inten = np.where(pts[:, 0] > 1.0, 0.7, 0.2)
        y = np.arange(0.3, 1.7, 0.01)
        chain = np.stack([1.03 + 0.05 * (y - 1.0), y], axis=1)
        normals = np.tile([1.0, 0.0], (y.size, 1))
        kw = dict(eps=0.2, min_points=18, half_across=0.25, width=0.05)
        p, _, _ = fit_step_lines(chain, normals, pts, inten, cKDTree(pts), **kw)
        # The outline's direction is known modulo 90 degrees: 90 stands for 0 too.
        q, n, fitted = fit_step_lines(chain, normals, pts, inten, cKDTree(pts), axis_angle=np.radians(90.0),
                                      axis_snap_deg=12.0, **kw)
        assert fitted.all() and np.allclose(n, [1.0, 0.0])
        free.append(np.abs(p[:, 0] - 1.0).max())
        square.append(np.abs(q[:, 0] - 1.0).max())
    assert np.median(square) < 0.01 and np.median(square) < 0.5 * np.median(free)


def test_edge_far_from_square_to_the_outline_keeps_its_own_tilt():
    rng = np.random.default_rng(3)
    pts = rng.random((1600, 2)) * 2.0
    along = (pts - 1.0) @ np.array([np.cos(np.radians(30)), np.sin(np.radians(30))])
    inten = np.where(along > 0.0, 0.7, 0.2)
    t = np.arange(-0.6, 0.6, 0.01)
    n30 = np.array([np.cos(np.radians(30)), np.sin(np.radians(30))])
    chain = 1.0 + t[:, None] * np.array([-n30[1], n30[0]])
    _, n, fitted = fit_step_lines(chain, np.tile(n30, (t.size, 1)), pts, inten, cKDTree(pts), eps=0.1, min_points=18,
                                  half_across=0.12, width=0.025, axis_angle=0.0, axis_snap_deg=12.0)
    assert fitted.all()
    assert np.all(np.abs(np.degrees(np.arctan2(n[:, 1], n[:, 0])) - 30.0) < 3.0)


def test_dominant_axis_of_a_rotated_rectangle_and_none_for_a_circle():
    a = np.radians(20.0)
    sides = np.array([[np.cos(a + k * np.pi / 2), np.sin(a + k * np.pi / 2)] for k in range(4)])
    normals = np.repeat(sides, [30, 10, 30, 10], axis=0)
    assert abs(np.degrees(dominant_axis(normals)) - 20.0) < 1e-6
    phi = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    assert dominant_axis(np.stack([np.cos(phi), np.sin(phi)], axis=1)) is None
    assert dominant_axis(np.zeros((0, 2))) is None
