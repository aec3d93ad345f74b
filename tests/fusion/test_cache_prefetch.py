"""The prefetch hints compile inside numba kernels and change no result."""

import numba as nb
import numpy as np
import pytest
from numba.core.errors import TypingError

from evpose.fusion.cache_prefetch import prefetch_read, prefetch_write


@nb.njit
def _gather(values, index, ahead):
    """Sum of ``values[index]`` with the element ``ahead`` positions on prefetched (0: none)."""
    total = 0.0
    for i in range(index.shape[0]):
        if ahead and i + ahead < index.shape[0]:
            prefetch_read(values, index[i + ahead])
        total += values[index[i]]
    return total


@nb.njit
def _scatter(out, index):
    """``out[index[i]] = i`` with each target prefetched for writing one step ahead."""
    for i in range(index.shape[0]):
        if i + 1 < index.shape[0]:
            prefetch_write(out, index[i + 1])
        out[index[i]] = i


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.uint64])
def test_gather_with_prefetch_gives_the_same_sum_for_every_index_type(dtype):
    rng = np.random.default_rng(3)
    values = rng.standard_normal(100_000)
    index = rng.integers(0, values.size, 5_000).astype(dtype)
    assert _gather(values, index, 16) == _gather(values, index, 0) == pytest.approx(values[index.astype(np.int64)].sum())


def test_scatter_with_write_prefetch_writes_what_it_would_without():
    rng = np.random.default_rng(4)
    index = rng.permutation(10_000)[:3_000]
    out = np.full(10_000, -1, np.int64)
    _scatter(out, index)
    expected = np.full(10_000, -1, np.int64)
    expected[index] = np.arange(index.size)
    assert np.array_equal(out, expected)


def test_prefetch_of_a_two_dimensional_array_is_refused_at_compile_time():
    @nb.njit
    def bad(a):
        prefetch_read(a, 0)

    with pytest.raises(TypingError):
        bad(np.zeros((2, 2)))
