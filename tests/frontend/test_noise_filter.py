"""Consistency noise filter: keeps events with recent neighbours, drops isolated ones, state survives batches."""

import numpy as np

from evpose.core.events import EventArray
from evpose.frontend.noise_filter import ConsistencyNoiseFilter, NoiseFilterConfig

W, H = 120, 90


def moving_edges_with_noise(seed=0, duration_us=200_000, noise_rate_hz=5_000.0):
    """Three vertical edges sweeping right at 200 px/s (one event per pixel crossed) plus uniform noise."""
    rng = np.random.default_rng(seed)
    t_cross = np.arange(0, duration_us, 5_000)  # edge advances one column every 5 ms
    ts, xs, ys = [], [], []
    for x0 in (10, 40, 70):
        for k, tc in enumerate(t_cross):
            rows = np.arange(20, 70)
            ts.append(tc + rng.integers(0, 1_000, rows.size))
            xs.append(np.full(rows.size, x0 + k))
            ys.append(rows)
    t_sig = np.concatenate(ts)
    n_noise = rng.poisson(noise_rate_hz * duration_us * 1e-6)
    t = np.concatenate([t_sig, rng.integers(0, duration_us, n_noise)])
    x = np.concatenate([np.concatenate(xs), rng.integers(0, W, n_noise)])
    y = np.concatenate([np.concatenate(ys), rng.integers(0, H, n_noise)])
    signal = np.concatenate([np.ones(t_sig.size, bool), np.zeros(n_noise, bool)])
    order = np.argsort(t, kind="stable")
    ev = EventArray.from_arrays(t[order], x[order], y[order], np.where(rng.random(t.size) < 0.5, 1, -1).astype(np.int8))
    return ev, signal[order]


def test_noise_filter_keeps_signal_and_removes_isolated_noise():
    ev, signal = moving_edges_with_noise()
    keep = ConsistencyNoiseFilter(NoiseFilterConfig(window_us=5_000), W, H).filter(ev)
    assert keep[signal].mean() >= 0.95
    assert (~keep[~signal]).mean() >= 0.80


def test_noise_filter_keeps_an_event_whose_neighbour_fired_within_the_window():
    ev = EventArray.from_arrays([0, 3_000, 20_000, 30_000], [5, 6, 30, 31], [5, 5, 5, 6], [1, 1, 1, -1])
    keep = ConsistencyNoiseFilter(NoiseFilterConfig(window_us=5_000), W, H).filter(ev)
    assert keep.tolist() == [False, True, False, False]  # 10 ms gap > T for the last pair


def test_noise_filter_is_stateful_across_batches():
    ev, _ = moving_edges_with_noise(seed=1)
    whole = ConsistencyNoiseFilter(NoiseFilterConfig(), W, H).filter(ev)
    f = ConsistencyNoiseFilter(NoiseFilterConfig(), W, H)
    parts = np.concatenate([f.filter(ev[a:b]) for a, b in ((0, 1000), (1000, 1001), (1001, len(ev)))])
    assert np.array_equal(whole, parts)


def test_noise_filter_handles_border_pixels():
    ev = EventArray.from_arrays([0, 10], [0, 1], [0, 0], [1, 1])
    keep = ConsistencyNoiseFilter(NoiseFilterConfig(), W, H).filter(ev)
    assert keep.tolist() == [False, True]
    ev = EventArray.from_arrays([0, 10], [W - 1, W - 2], [H - 1, H - 1], [1, 1])
    assert ConsistencyNoiseFilter(NoiseFilterConfig(), W, H).filter(ev).tolist() == [False, True]


def test_disabled_noise_filter_keeps_everything_but_still_tracks_pixels():
    ev, _ = moving_edges_with_noise(seed=2)
    f = ConsistencyNoiseFilter(NoiseFilterConfig(enabled=False), W, H)
    assert f.filter(ev).all()
    on = ConsistencyNoiseFilter(NoiseFilterConfig(enabled=True), W, H)
    on.filter(ev)
    assert np.array_equal(f.last_timestamps, on.last_timestamps)


def test_noise_filter_snapshot_restore_replays_identically():
    ev, _ = moving_edges_with_noise(seed=3)
    f = ConsistencyNoiseFilter(NoiseFilterConfig(), W, H)
    f.filter(ev[:5000])
    snap = f.snapshot()
    first = f.filter(ev[5000:])
    f.filter(ev[:100])  # disturb the state
    f.restore(snap)
    assert np.array_equal(f.filter(ev[5000:]), first)
