"""``event_window.mean_time_us`` equals ``int(np.mean(t))`` bit for bit, on landing-like and on epoch-sized times."""
import numpy as np

from evpose.slam.event_window import mean_time_us


def test_mean_time_equals_numpy_mean():
    rng = np.random.default_rng(0)
    for n in (1, 2, 7, 300, 4097, 8193, 40000):
        for base in (0, 1_234_567, 3_000_000_000, 1_733_000_000_000_000, -5_000_000):
            t = np.sort(base + rng.integers(0, 40_000, n)).astype(np.int64)
            assert mean_time_us(t) == int(np.mean(t))
    big = np.array([2**62, 2**62 - 1, 2**61], np.int64)  # beyond exact sums: numpy's mean is used
    assert mean_time_us(big) == int(np.mean(big))
