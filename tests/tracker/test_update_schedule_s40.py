"""``UpdateSchedule`` looks its segments up with ``bisect`` on Python ints: every update's grid index and gap are those
the segment arrays give by ``np.searchsorted``, and the indices are Python ints (the session adds them to times)."""

import numpy as np

from evpose.core.stream_gaps import EventGap
from evpose.tracker.event_gaps import UpdateSchedule


def test_grid_and_gaps_match_the_segment_arrays_at_every_update():
    gaps = [EventGap(95, 3_000), EventGap(3_100, 3_140), EventGap(5_000, 9_000), EventGap(9_010, 20_000)]
    s = UpdateSchedule(gaps, t0_us=0, dt_us=10, t_end_us=25_000, warmup_us=30)
    assert s.total > 100 and len(s.gaps) >= 2
    for u in range(0, s.total + 3):
        k = int(np.searchsorted(s._u0, u, side="right")) - 1
        want_grid = 0 if u <= 0 else int(s._k0[k] + (u - s._u0[k]))
        want_gap = None if u <= 0 or u > s.total else (s._gaps[k] if u == s._u0[k] else None)
        if u <= s.total:
            got = s.grid(u)
            assert got == want_grid and type(got) is int
        assert s.gap_of(u) == want_gap
    assert [s.gap_of(u) for u in range(1, s.total + 1) if s.gap_of(u) is not None] == s.gaps


def test_an_empty_schedule_has_no_updates():
    s = UpdateSchedule([], t0_us=100, dt_us=10, t_end_us=100, warmup_us=0)
    assert s.total == 0 and s.grid(1) == 0 and s.gap_of(1) is None
