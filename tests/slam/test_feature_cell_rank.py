"""``features.rank_in_runs`` (the per-cell rank of ``detect_features``) equals the loop over the runs it replaced."""
import numpy as np

from evpose.slam.features import rank_in_runs


def _rank_loop(cell):
    rank = np.zeros(len(cell), int)
    starts = np.flatnonzero(np.r_[True, cell[1:] != cell[:-1]])
    for s, e in zip(starts, np.r_[starts[1:], len(cell)]):
        rank[s:e] = np.arange(e - s)
    return rank


def test_rank_in_runs_equals_the_loop_over_runs():
    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 17, 200, 1000):
        for hi in (1, 3, 40):
            cell = np.sort(rng.integers(0, hi, n))
            got = rank_in_runs(cell)
            assert got.dtype == _rank_loop(cell).dtype
            np.testing.assert_array_equal(got, _rank_loop(cell))
