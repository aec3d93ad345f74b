"""The compiled / wrapper-free forms of the tracker's per-update steps give the numpy expressions' results bit for bit."""

import evpose  # noqa: F401  (BLAS pin before numpy)

import numpy as np
import pytest

from evpose.core import lapack_calls
from evpose.tracker.crowding import crowded_points, uncrowded
from evpose.tracker.registration import polarity_trail, strided_subset, subsample_indices
from evpose.tracker.visible_map import VisibleMap, VisibleMapConfig, visible_points
from evpose.tracker.wall_occlusion import hidden_by_walls, visible_over_walls

K = np.array([[200.0, 0.0, 170.0], [0.0, 200.0, 130.0], [0.0, 0.0, 1.0]])
DOWN = np.array([[1.0, 0, 0, 0.1], [0, -1.0, 0, -0.05], [0, 0, -1.0, 3.0], [0, 0, 0, 1.0]])
"""Camera 3 m above the ground looking down."""


def _ground_points(rng, n=3000):
    pts = np.c_[rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(0.0, 0.3, n)]
    tangents = rng.normal(size=(n, 3))
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    tangents[::17] = 0.0  # unknown tangents: never crowded themselves
    return np.ascontiguousarray(pts), np.ascontiguousarray(tangents)


def test_visible_over_walls_drops_exactly_the_points_hidden_by_walls():
    rng = np.random.default_rng(1)
    pts, normals = _ground_points(rng)
    feet = rng.random(len(pts)) < 0.3
    index = np.sort(rng.choice(len(pts), 1200, replace=False))
    for centre in (np.array([0.5, 0.0, 3.0]), np.array([-2.0, 1.0, 1.0])):
        expected = index[~hidden_by_walls(pts, normals, feet, index, centre)]
        got = visible_over_walls(pts, normals, feet, index, centre)
        assert got.dtype == np.int64 and np.array_equal(got, expected)
        assert 0 < got.size < index.size


def test_uncrowded_returns_the_points_crowded_points_keeps_with_their_rows():
    rng = np.random.default_rng(2)
    pts, tangents = _ground_points(rng)
    used = np.sort(rng.choice(len(pts), 1500, replace=False))
    sel, p, t = uncrowded(pts, tangents, used, DOWN, K, 3.0, 1.0)
    alone = ~crowded_points(np.take(pts, used, axis=0), np.take(tangents, used, axis=0), DOWN, K, 3.0, 1.0)
    assert 0 < alone.sum() < used.size
    assert np.array_equal(sel, used[alone])
    assert np.array_equal(p, pts[used[alone]]) and np.array_equal(t, tangents[used[alone]])
    assert p.flags.c_contiguous and t.flags.c_contiguous


@pytest.mark.parametrize("n, max_points", [(5000, 1000), (1001, 1000), (1000, 1000), (7, 1000), (0, 1000), (12345, 777)])
def test_strided_subset_equals_indexing_with_subsample_indices(n, max_points):
    values = np.arange(n, dtype=np.int64) * 3 + 1
    assert np.array_equal(strided_subset(values, max_points), values[subsample_indices(n, max_points)])


def test_polarity_trail_equals_the_nested_where():
    p = np.array([-1, 0, 1, 1, -1, 0, 0], np.int8)
    expected = np.where(p < 0, 0.25, np.where(p > 0, -0.25, 0.6))
    assert np.array_equal(polarity_trail(p, 0.25, -0.25, 0.6), expected)


def test_lapack_calls_equal_numpys_bit_for_bit_and_raise_as_numpy_does():
    rng = np.random.default_rng(3)
    for n in (4, 6, 12):
        A = rng.normal(size=(n, n))
        S = A @ A.T + np.eye(n)
        B = rng.normal(size=(n, 7))
        w, v = lapack_calls.eigh(S)
        w0, v0 = np.linalg.eigh(S)
        assert np.array_equal(w, w0) and np.array_equal(v, v0)
        assert np.array_equal(lapack_calls.inv(S[: n // 2 * 2, : n // 2 * 2]), np.linalg.inv(S[: n // 2 * 2, : n // 2 * 2]))
        assert np.array_equal(lapack_calls.solve(S, B), np.linalg.solve(S, B))
    singular = np.zeros((6, 6))
    with pytest.raises(np.linalg.LinAlgError):
        lapack_calls.inv(singular)
    with pytest.raises(np.linalg.LinAlgError):
        lapack_calls.solve(singular, np.ones((6, 2)))


def test_visible_map_cache_equals_a_fresh_cull_along_a_slow_motion():
    rng = np.random.default_rng(4)
    pts, _ = _ground_points(rng, 20000)
    vm = VisibleMap(pts, K, 346, 260)
    cfg = VisibleMapConfig()
    T = DOWN.copy()
    for k in range(30):  # small steps: the superset is reused most of the time, rebuilt now and then
        T[:3, 3] += np.array([0.01, -0.004, 0.002])
        c, s = np.cos(0.002 * k), np.sin(0.002 * k)
        T[:3, :3] = DOWN[:3, :3] @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        assert np.array_equal(vm.visible(T, cfg), visible_points(pts, T, K, 346, 260, cfg))
