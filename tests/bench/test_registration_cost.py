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


def test_cost_table_subsets_the_per_point_keyword_arguments_with_the_points(monkeypatch):
    import types

    import evpose.tracker.registration as registration
    from evpose.bench.registration_cost import POINT_COUNTS, registration_cost_table

    seen = []

    def fake_register(levels, pts, *args, tangents_world=None, trail_offsets_px=None, **kwargs):
        assert tangents_world.shape == (pts.shape[0], 3) and trail_offsets_px.shape == (pts.shape[0],)
        seen.append(pts.shape[0])
        return types.SimpleNamespace(iterations=2)

    monkeypatch.setattr(registration, "register_to_map", fake_register)
    m = max(POINT_COUNTS) + 7
    call = ([object()], np.zeros((m, 3)), (np.eye(4), np.eye(3), None, None), {"tangents_world": np.zeros((m, 3)),
                                                                             "trail_offsets_px": np.zeros(m)})
    out = registration_cost_table([call], repeats=1)
    assert sorted(set(seen)) == sorted(set(min(c, m) for c in POINT_COUNTS))
    assert np.isfinite(out["fit_fixed_per_call_us"])
