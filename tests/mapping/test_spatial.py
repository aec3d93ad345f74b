"""BoxIndex returns exactly the points a brute-force box test returns."""

from __future__ import annotations

import numpy as np

from evpose.mapping.spatial import BoxIndex


def test_box_queries_match_brute_force():
    rng = np.random.default_rng(0)
    pts = rng.random((20000, 3)) * [20.0, 10.0, 3.0] - [5.0, 2.0, 0.0]
    index = BoxIndex(pts)
    for _ in range(30):
        lo = rng.random(3) * [20.0, 10.0, 3.0] - [6.0, 3.0, 0.5]
        hi = lo + rng.random(3) * [8.0, 5.0, 2.0]
        expect = np.flatnonzero(np.all((pts >= lo) & (pts <= hi), axis=1))
        assert np.array_equal(index.query(lo, hi), expect)


def test_box_outside_the_cloud_is_empty():
    index = BoxIndex(np.random.default_rng(1).random((100, 3)))
    assert index.query(np.array([5.0, 5.0, 0.0]), np.array([6.0, 6.0, 1.0])).size == 0
