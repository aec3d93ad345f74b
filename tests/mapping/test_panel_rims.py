"""Rims of panels proud of a wall: placed by where the panel's points end, pieces joined, corners closed."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.panel_rims import join_panel_rims, panel_edge_shift, panel_side

PANEL_I, WALL_I = 0.1, 0.7


def _panel_over_wall(seed, density=100.0, side_sigma=0.005, n_side=4):
    """2D cloud of a wall over [-1, 1] x [0, 2] with a panel over x < 0: front points, the wall behind, side-face points at x = 0.

    Returns points (N, 2), intensity (N,), layer (N,): +1 front, -1 hidden (behind the panel), 0 plain.
    """
    rng = np.random.default_rng(seed)
    wall = rng.random((rng.poisson(4 * density), 2)) * [2.0, 2.0] - [1.0, 0.0]
    front = rng.random((rng.poisson(2 * density), 2)) * [1.0, 2.0] - [1.0, 0.0]
    side = np.column_stack([rng.normal(0.0, side_sigma, n_side), rng.random(n_side) * 2.0])
    pts = np.concatenate([wall, front, side])
    inten = np.concatenate([np.full(len(wall), WALL_I), np.full(len(front), PANEL_I), np.full(len(side), PANEL_I)])
    layer = np.concatenate([np.where(wall[:, 0] < 0, -1, 0), np.ones(len(front)), -np.ones(len(side))]).astype(np.int8)
    return pts, inten, layer


def test_panel_side_finds_the_front_layer_and_not_a_plain_plane():
    pts, _, layer = _panel_over_wall(0)
    assert panel_side(pts[:, 0], layer) == -1.0
    assert panel_side(-pts[:, 0], layer) == 1.0
    rng = np.random.default_rng(1)
    plain = (rng.random(400) < 0.01).astype(np.int8)  # range-noise outliers on one layer
    assert panel_side(rng.random(400) - 0.5, plain) == 0.0


def _placed_rims(n_side):
    out = []
    for seed in range(20):
        pts, inten, layer = _panel_over_wall(seed, n_side=n_side)
        line = 0.03  # where a step fit left it: 3 cm outside the panel
        band = np.abs(pts[:, 0] - line) <= 0.25
        s = panel_edge_shift(pts[band, 0] - line, inten[band], layer[band], -0.25, 0.25, 0.5 * (PANEL_I + WALL_I))
        assert s is not None
        out.append(line + s)
    return np.array(out)


def test_rim_is_placed_where_the_panel_points_end():
    err = _placed_rims(n_side=0)
    assert abs(err.mean()) < 0.004 and np.median(np.abs(err)) < 0.01


def test_side_face_points_push_the_rim_out_by_less_than_a_step_fit():
    # Side-face points sit on the rim itself: the second outermost panel point is one of them
    # and the rim lands about 2 / density-along-the-normal (1 cm here) outside - not the 3 cm
    # a step fit centred in the gap beyond them gave.
    err = _placed_rims(n_side=4)
    assert 0.0 < err.mean() < 0.015 and np.median(err) < 0.015


def test_pieces_of_one_rim_are_placed_together_and_gaps_to_a_corner_closed():
    pts, inten, layer = _panel_over_wall(3, density=400.0)
    # The panel's top rim at y = 1.6: above it, the wall alone.
    above = pts[:, 1] >= 1.6
    keep = ~(above & (inten == PANEL_I))
    pts, inten, layer = pts[keep], inten[keep], np.where(above, 0, layer)[keep].astype(np.int8)
    tree = cKDTree(pts)
    # Two pieces of the side rim (x = 0) a centimetre apart and off; the top rim (y = 1.6) from x -0.8 to -0.1.
    y1, y2 = np.arange(0.2, 0.7, 0.01), np.arange(0.8, 1.3, 0.01)
    side = np.concatenate([np.column_stack([np.full(y1.size, 0.02), y1]), np.column_stack([np.full(y2.size, 0.03), y2])])
    x3 = np.arange(-0.8, -0.1, 0.01)
    top = np.column_stack([x3, np.full(x3.size, 1.6)])
    p = np.concatenate([side, top])
    n = np.concatenate([np.tile([1.0, 0.0], (len(side), 1)), np.tile([0.0, 1.0], (len(top), 1))])
    q, m = join_panel_rims(p, n, pts, inten, layer, tree, half_across=0.15, max_gap=0.5, spacing=0.01)
    assert np.ptp(q[:len(side), 0]) < 1e-9 and abs(q[0, 0]) < 0.01  # one line, on the rim
    assert np.allclose(m[:len(side)], [1.0, 0.0])
    added = q[len(p):]
    # The side rim continued up to the top rim's line, the top rim to the side's.
    assert added.shape[0] > 0
    assert added[:, 1].max() > 1.55 and added[:, 0].max() > -0.02


def test_a_rim_without_a_panel_beside_it_is_left_alone():
    rng = np.random.default_rng(4)
    pts = rng.random((1600, 2)) * 2.0 - [1.0, 0.0]
    inten = np.where(pts[:, 0] < 0, PANEL_I, WALL_I)  # paint: one layer
    layer = np.zeros(len(pts), np.int8)
    y = np.arange(0.2, 1.8, 0.01)
    p = np.column_stack([np.full(y.size, 0.02), y])
    n = np.tile([1.0, 0.0], (y.size, 1))
    q, m = join_panel_rims(p, n, pts, inten, layer, cKDTree(pts), half_across=0.15, max_gap=0.5)
    assert np.array_equal(q, p) and np.array_equal(m, n)
