"""Which pose updates a tracking session runs: the regular grid, minus the empty updates inside long event gaps.

A session updates the pose at ``t0 + k * dt`` (``k = 1, 2, ...``). Where the events stop for longer than
``TrackerConfig.max_event_gap_ms`` (a recorder paused, two flights in one file, a dropped stream) the updates in
between have nothing to register, and stepping through them was slow and harmful. The updates up to the one that
takes the last event before the gap run as before; one update then stands for the whole gap, at the first grid time
at least ``warmup_ms`` after the first event after it. It reports the track lost ("no events for ... s") and
restarts the tracker there as at the start of the recording (from which pose:
:meth:`~evpose.tracker.session.TrackingSession._restart_after_gap`).

Measured (session 25, demo ``landing`` with everything after 2 s moved later, IMU and ground truth too, ``full``,
``/tmp/s25/cli25/make_gap.py``, ``cmp_gap.py``): a 60 s gap was 12 793 updates, 30.5 s and 1.56 GB, every one of
them written as an IMU-bridged ("degraded") pose with no IMU in the gap either, 7 km off on average after it, exit
0; now 788 updates, 6.6 s, 0.40 GB, exit 1 naming the gap, and after it 10.45 mm ATE (the uninterrupted run over the
same stretch 7.44 mm; before the gap unchanged, 12.00 mm). A 1 h gap (720 000 updates) was stopped after 150 s at
11.0 GB resident, about a tenth of the way (it could not have finished on this machine); now 5.5 s, 0.39 GB, the
same poses as the 60 s gap. ``evpose slam`` was not slowed by the gap (its windows follow the events: 17 s).

In the fused modes a stretch without IMU samples is a gap too (:func:`evpose.core.stream_gaps.merge_gaps` joins it with an event gap it
overlaps), and so is the end of a recording whose IMU stops before its events (the last update then says so, with
no restart). They were bridged by interpolating across the hole, or by holding the last sample: the demo ``landing``
with its IMU cut at 2 s wrote its last 2 s 0.68 m RMS off (2.5 m at most), exit 0, now 394 poses to 2.0 s (12.00 mm)
and exit 1 naming the IMU's end; with a 1 s hole from 1.5 s it was 4.4 m RMS off after the hole, now 17.4 mm.

Without ground truth (``--init``) the restart was from the last estimate with the velocity unknown, which is right
for a camera that stood still during the gap. In the splice above the camera moved on at 3.3 m/s, 0.1 m from the
last estimate when tracking restarted: the fusion did not catch up and wrote the 394 updates after the gap 3.45 m
RMS off (exit 1 for the gap). Tried and left out: reporting the fused modes' updates after a restart lost until the
map is acquired again (5 strict registrations in a row): it did not help there (a wrong lock 1.5 m off passed the
strict test, 78 of 759 points; still 4.2 m RMS over the 291 poses written) and cost the restart from ground truth
37 updates (12.92 against 10.45 mm). The polarity filter's hold for an unknown velocity is set again at such a
restart, as at a start without one (no change in that run).

Session 26 built a search for the pose for such a restart (:mod:`evpose.tracker.reacquisition`,
``reacquisition.enabled``, off by default): pose hypotheses around the last estimate, each tracked with the last
estimated velocity, the best accepted only with a chance-level z of 16 and 1.3 times the runner-up's; until then the
updates are lost, naming the search. The splice above is found again after 43 updates and written 13.6 mm RMS off (351
poses); where the camera flew on 0.2-1 s during the pause (0.7-2.5 m on, its velocity changed by 0.8-4.6 m/s) it is
not found and nothing is written after the gap (the restart from the last estimate: 3.0-3.8 m RMS off). But with the
pause at 1.0 / 1.5 / 3.0 s the restart from the last estimate recovers by itself (61 / 57 / 46 mm RMS after it) and the
search did worse (nothing written / a 44 mm lock that then drifted to 790 mm / nothing): hence off. A velocity that is
unknown, not the pose, is what kept the fusion off at 2 s: from the true pose with the velocity unknown it was 3.37 m
RMS off too.

:class:`UpdateSchedule` maps the session's update count to grid indices and back in O(log gaps): the cost of a gap
no longer depends on its length.
"""

from __future__ import annotations

import numpy as np

from evpose.core.stream_gaps import EventGap

DEFAULT_MAX_EVENT_GAP_MS = 1000.0
"""``TrackerConfig.max_event_gap_ms``'s default (here so that ``evpose info`` can name it without importing the tracker)."""


class UpdateSchedule:
    """Grid index per update of a session whose events end at ``t_end_us``: update ``u`` (1-based) is at
    ``t0 + grid(u) * dt``. Updates run in segments of consecutive grid indices; the first update of every segment
    but one starting at grid index 1 is a gap's update (:meth:`gap_of`)."""

    def __init__(self, gaps: list[EventGap], t0_us: int, dt_us: int, t_end_us: int, warmup_us: int):
        last = max((int(t_end_us) - int(t0_us)) // int(dt_us), 0)
        starts: list[int] = []
        ends: list[int] = []
        jumps: list[EventGap | None] = []
        start, jump = 1, None
        for g in gaps:
            k_last = max((g.t_last_us - t0_us) // dt_us + 1, 0)  # the update that takes the gap's last event
            k_restart = min(-((t0_us - g.t_next_us - warmup_us) // dt_us), last)
            if k_restart <= k_last + 1 or k_restart < start:
                continue  # no update to skip (a coarse grid), or past the end
            if k_last < start:
                # The events between the previous gap and this one end before the previous restart: one update
                # stands for both gaps.
                jump = EventGap(jump.t_last_us if jump is not None else g.t_last_us, g.t_next_us,
                                g.stream if jump is None or jump.stream == g.stream else "events or IMU samples")
            else:
                starts.append(start), ends.append(k_last), jumps.append(jump)
                jump = g
            start = k_restart
        if start <= last:
            starts.append(start), ends.append(last), jumps.append(jump)
        keep = [i for i in range(len(starts)) if ends[i] >= starts[i]]
        self._k0 = np.array([starts[i] for i in keep], dtype=np.int64)
        lengths = np.array([ends[i] - starts[i] + 1 for i in keep], dtype=np.int64)
        self._u0 = np.concatenate([[1], 1 + np.cumsum(lengths)[:-1]]).astype(np.int64) if keep else np.zeros(0, np.int64)
        self._len = lengths
        self._gaps = [jumps[i] for i in keep]
        self.total = int(lengths.sum())
        """Number of updates a full run makes."""

    @property
    def gaps(self) -> list[EventGap]:
        """The gaps one update each stands for, in time order."""
        return [g for g in self._gaps if g is not None]

    def grid(self, u: int) -> int:
        """Grid index of update ``u`` (1-based; 0 -> 0, the start)."""
        if u <= 0 or not self.total:
            return 0
        s = int(np.searchsorted(self._u0, u, side="right")) - 1
        return int(self._k0[s] + (u - self._u0[s]))

    def gap_of(self, u: int) -> EventGap | None:
        """The gap update ``u`` stands for, None for a regular update."""
        if u <= 0 or u > self.total:
            return None
        s = int(np.searchsorted(self._u0, u, side="right")) - 1
        return self._gaps[s] if u == self._u0[s] else None

    def updates_until(self, k: int) -> int:
        """How many updates lie at grid index ``k`` or before."""
        s = int(np.searchsorted(self._k0, k, side="right")) - 1
        if s < 0:
            return 0
        return int(self._u0[s] + min(k - self._k0[s], self._len[s] - 1))
