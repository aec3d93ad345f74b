"""Peer comparison with dv-processing: both noise filters keep the same events when configured alike."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.core.events import EventArray

pytest.importorskip("dv_processing")


def clustered_events(seed: int = 0, n: int = 20_000) -> EventArray:
    """Half random noise, half events in short bursts along a line (which the filters keep)."""
    rng = np.random.default_rng(seed)
    t_noise = rng.integers(0, 500_000, n // 2)
    t_line = rng.integers(0, 500_000, n // 2)
    x = np.concatenate([rng.integers(0, 80, n // 2), (t_line // 10_000) % 80])
    y = np.concatenate([rng.integers(0, 60, n // 2), rng.integers(20, 24, n // 2)])
    t = np.concatenate([t_noise, t_line])
    order = np.argsort(t, kind="stable")
    return EventArray.from_arrays(t[order], x[order], y[order], rng.integers(0, 2, n)[order])


def test_noise_filters_configured_alike_keep_the_same_events():
    from evpose.bench.peers import compare

    r = compare(clustered_events(), 80, 60, window_us=3000, repeats=1)
    assert r["kept_only_ours"] == 0 and r["kept_only_dv"] == 0 and r["kept_agreement"] == 1.0
    assert 0 < r["kept_ours"] < r["events_judged"]  # the filter really removes some and keeps some
    for key in ("noise_filter_ours_mev_s", "noise_filter_dv_mev_s", "time_surface_ours_mev_s", "time_surface_dv_mev_s"):
        assert r[key] > 0
