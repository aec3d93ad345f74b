"""UpdateSchedule: the regular update grid, minus the empty updates inside long event gaps, in O(log gaps)."""

import numpy as np

from evpose.core.stream_gaps import EventGap
from evpose.tracker.event_gaps import UpdateSchedule


def test_without_gaps_every_grid_step_is_an_update():
    s = UpdateSchedule([], t0_us=100, dt_us=10, t_end_us=1_000, warmup_us=0)
    assert s.total == 90 and [s.grid(u) for u in (0, 1, 50, 90)] == [0, 1, 50, 90]
    assert s.updates_until(-3) == 0 and s.updates_until(40) == 40 and s.gap_of(1) is None and s.gaps == []


def test_a_long_gap_is_one_update_at_the_first_grid_time_a_warmup_after_it():
    # events until 295, then nothing until 10_000_000; grid t0 = 0, dt = 10, warm-up 30
    gap = EventGap(295, 10_000_000)
    s = UpdateSchedule([gap], t0_us=0, dt_us=10, t_end_us=10_000_500, warmup_us=30)
    assert s.grid(30) == 30  # the update at t = 300 takes the last event before the gap
    assert s.grid(31) == 1_000_003 and s.gap_of(31) == gap  # t = 10_000_030: one update stands for the gap
    assert s.grid(32) == 1_000_004 and s.gap_of(32) is None
    assert s.total == 30 + 1 + (1_000_050 - 1_000_003)
    # time -> updates at or before it
    assert s.updates_until(30) == 30 and s.updates_until(500_000) == 30 and s.updates_until(1_000_003) == 31
    assert s.updates_until(1_000_050) == s.total


def test_a_short_burst_between_two_gaps_joins_them_into_one_update():
    gaps = [EventGap(95, 5_000_000), EventGap(5_000_010, 9_000_000)]
    s = UpdateSchedule(gaps, t0_us=0, dt_us=10, t_end_us=9_001_000, warmup_us=30)
    assert s.gaps == [EventGap(95, 9_000_000)] and s.grid(11) == 900_003


def test_a_gap_before_the_last_event_ends_the_run_with_its_update():
    s = UpdateSchedule([EventGap(95, 7_000_000)], t0_us=0, dt_us=10, t_end_us=7_000_000, warmup_us=30)
    assert s.total == 11 and s.grid(11) == 700_000 and s.gap_of(11) is not None
