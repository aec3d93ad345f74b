"""ESIM event generation: threshold crossings, interpolated timestamps, refractory period, polarity."""

import numpy as np

from evpose.sim.esim import EsimConfig, EventGenerator


def _gen(width=4, height=1, **kw):
    cfg = EsimConfig(c_sigma=0.0, refractory_us=0, **kw)
    return EventGenerator(cfg, width, height, np.random.default_rng(0))


def test_linear_ramp_emits_one_event_per_threshold_at_interpolated_times():
    gen = _gen(width=1, c_pos=0.25)
    gen.reset(np.zeros((1, 1)), 0)
    ev = gen.step(np.full((1, 1), 1.0), 1000)  # +1.0 log units over 1 ms -> crossings at 0.25, 0.5, 0.75, 1.0
    assert len(ev) == 4
    assert np.all(ev.p == 1)
    np.testing.assert_array_equal(ev.t, [250, 500, 750, 1000])


def test_decreasing_intensity_gives_off_events_and_reference_carries_over():
    gen = _gen(width=1, c_neg=0.3)
    gen.reset(np.zeros((1, 1)), 0)
    ev1 = gen.step(np.full((1, 1), -0.5), 100)
    ev2 = gen.step(np.full((1, 1), -0.7), 200)  # reference is at -0.3; -0.6 is crossed during the 2nd step
    assert len(ev1) == 1 and ev1.p[0] == -1 and ev1.t[0] == 60
    assert len(ev2) == 1 and ev2.p[0] == -1 and ev2.t[0] == 150


def test_refractory_period_drops_events_closer_than_it():
    cfg = EsimConfig(c_pos=0.125, c_sigma=0.0, refractory_us=300)
    gen = EventGenerator(cfg, 1, 1, np.random.default_rng(0))
    gen.reset(np.zeros((1, 1)), 0)
    ev = gen.step(np.full((1, 1), 1.0), 1000)  # crossings every 125 us
    np.testing.assert_array_equal(ev.t, [125, 500, 875])


def test_events_are_sorted_across_pixels():
    gen = _gen(width=3, c_pos=0.1)
    gen.reset(np.zeros((1, 3)), 0)
    ev = gen.step(np.array([[0.35, 0.95, 0.15]]), 1000)
    assert np.all(np.diff(ev.t) >= 0)
    assert sorted(np.unique(ev.x).tolist()) == [0, 1, 2]


def test_threshold_spread_is_seeded():
    cfg = EsimConfig(c_sigma=0.05)
    a = EventGenerator(cfg, 8, 8, np.random.default_rng(3))
    b = EventGenerator(cfg, 8, 8, np.random.default_rng(3))
    assert np.array_equal(a.c_pos, b.c_pos) and a.c_pos.std() > 0
