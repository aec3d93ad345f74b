"""Corners of brightness-edge chains: consecutive fitted lines continued to where they cross."""

from __future__ import annotations

import numpy as np

from evpose.mapping.albedo_corners import complete_corners, line_runs

SP = 0.01


def _corner_chain(round_m: float = 0.15):
    """An L: a line along y = 0 (x 0 .. 1 - round_m), a quarter circle of radius round_m, a line along x = 1 up to y = 1.

    Lines' points are 'fitted' (normals constant per line); the arc is not."""
    a = np.stack([np.arange(0.0, 1.0 - round_m, SP), np.zeros(int(round((1.0 - round_m) / SP)))], axis=1)
    t = np.linspace(0.0, 0.5 * np.pi, 20)[1:-1]
    arc = np.stack([1.0 - round_m + round_m * np.sin(t), round_m - round_m * np.cos(t)], axis=1)
    b = np.stack([np.ones(int(round((1.0 - round_m) / SP))), np.arange(round_m, 1.0, SP)], axis=1)
    p = np.concatenate([a, arc, b])
    n = np.concatenate([np.tile([0.0, 1.0], (a.shape[0], 1)),
                        np.stack([-np.sin(t), np.cos(t)], axis=1),
                        np.tile([-1.0, 0.0], (b.shape[0], 1))])
    fitted = np.concatenate([np.ones(a.shape[0], bool), np.zeros(arc.shape[0], bool), np.ones(b.shape[0], bool)])
    return p, n, fitted


def test_line_runs_split_fitted_points_by_their_shared_normal():
    p, n, fitted = _corner_chain()
    runs = line_runs(n, fitted)
    assert len(runs) == 2
    assert runs[0][0] == 0 and fitted[runs[1][0]:runs[1][1]].all()


def test_a_rounded_corner_is_replaced_by_the_two_lines_meeting_at_their_crossing():
    p, n, fitted = _corner_chain(0.15)
    q, m = complete_corners(p, n, fitted, SP, 45.0, 0.3, 10)
    # Every point now lies on one of the two lines, and the crossing (1, 0) is on the chain.
    on_a = np.abs(q[:, 1]) < 1e-9
    on_b = np.abs(q[:, 0] - 1.0) < 1e-9
    assert np.all(on_a | on_b)
    assert np.min(np.hypot(q[:, 0] - 1.0, q[:, 1])) < 1e-9
    # Normals follow their line; the spacing stays about the contour spacing.
    assert np.allclose(m[on_a & ~on_b], [0.0, 1.0]) and np.allclose(m[on_b & ~on_a], [-1.0, 0.0])
    gaps = np.linalg.norm(np.diff(q, axis=0), axis=1)
    assert gaps.max() <= 1.5 * SP + 1e-9


def test_a_corner_beyond_the_reach_is_left_as_traced():
    p, n, fitted = _corner_chain(0.15)
    q, m = complete_corners(p, n, fitted, SP, 45.0, 0.05, 10)
    assert np.array_equal(q, p) and np.array_equal(m, n)


def test_lines_at_a_shallow_angle_are_no_corner():
    a = np.stack([np.arange(0.0, 0.5, SP), np.zeros(50)], axis=1)
    d = np.array([np.cos(0.3), np.sin(0.3)])
    b = a[-1] + SP + np.arange(50)[:, None] * SP * d
    p = np.concatenate([a, b])
    n = np.concatenate([np.tile([0.0, 1.0], (50, 1)), np.tile([-d[1], d[0]], (50, 1))])
    q, m = complete_corners(p, n, np.ones(100, bool), SP, 45.0, 0.3, 10)
    assert np.array_equal(q, p)
