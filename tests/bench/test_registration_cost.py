"""The registration cost benchmark's split of a call's latency into per-call, per-linearisation and per-point parts."""

import numpy as np

from evpose.bench.registration_cost import split_cost


def test_split_cost_recovers_the_three_parts_of_an_exact_linear_model():
    rng = np.random.default_rng(0)
    L = rng.integers(2, 8, 60).astype(float)
    M = rng.choice([25, 100, 1000], 60).astype(float)
    us = 40.0 + 9.0 * L + 0.07 * M * L
    fixed, per_lin, per_point = split_cost(L, M, us)
    assert np.allclose((fixed, per_lin, per_point), (40.0, 9.0, 0.07), rtol=1e-9)
