"""front_layer: the wall behind a proud panel is hidden, a single noisy plane and the wall beside the panel are not."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.visibility import front_layer


def _run(points, k=16, depth=0.012, radius_factor=3.0):
    d, idx = cKDTree(points).query(points, k=k)
    spacing = float(np.median(d[:, 1]))
    labels = np.zeros(points.shape[0], np.int32)
    return front_layer(points, labels, idx.astype(np.int64), np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), depth,
                       radius_factor * spacing)


def _plane(rng, n, lo, hi, z, noise):
    p = np.column_stack([rng.uniform(lo[0], hi[0], n), rng.uniform(lo[1], hi[1], n), np.full(n, z)])
    p[:, 2] += rng.normal(0.0, noise, n)
    return p


def test_wall_behind_a_proud_panel_is_hidden_and_the_panel_visible():
    rng = np.random.default_rng(0)
    wall = _plane(rng, 3600, (0, 0), (2, 2), 0.0, 0.005)  # 900 points/m^2
    panel = _plane(rng, 720, (0.6, 0.5), (1.4, 1.4), 0.02, 0.005)
    vis = _run(np.concatenate([wall, panel]))
    under = (wall[:, 0] > 0.7) & (wall[:, 0] < 1.3) & (wall[:, 1] > 0.6) & (wall[:, 1] < 1.3)
    assert vis[:3600][under].mean() < 0.1
    assert vis[3600:].mean() > 0.8
    far = (np.abs(wall[:, 0] - 1.0) > 0.6) | (np.abs(wall[:, 1] - 0.95) > 0.65)
    assert vis[:3600][far].mean() > 0.8


def test_single_noisy_plane_stays_mostly_visible():
    rng = np.random.default_rng(1)
    vis = _run(_plane(rng, 4000, (0, 0), (2, 2), 0.0, 0.005))
    assert vis.mean() > 0.75


def test_unlabelled_points_are_visible():
    rng = np.random.default_rng(2)
    p = _plane(rng, 500, (0, 0), (1, 1), 0.0, 0.005)
    d, idx = cKDTree(p).query(p, k=8)
    vis = front_layer(p, np.full(500, -1, np.int32), idx.astype(np.int64), np.zeros((1, 3)), np.array([[0.0, 0, 1]]), 0.0, 1.0)
    assert vis.all()
