"""Stretches of a sensor stream without samples (a recorder paused, two flights in one file, a dropped stream).

Both engines treat a long one as the end of what they track: the tracker restarts after it
(:mod:`evpose.tracker.event_gaps`), the SLAM ends its active map at it (:mod:`evpose.slam.system_gaps`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_CHUNK = 1 << 22
"""Events scanned for gaps per numpy call (bounded temporary memory on long recordings)."""


@dataclass(frozen=True)
class EventGap:
    """A stretch without events: ``t_last_us`` is the last event before it, ``t_next_us`` the first after it."""

    t_last_us: int
    t_next_us: int
    stream: str = "events"
    """What is missing: "events", "IMU samples" (the fused modes), or both."""

    @property
    def seconds(self) -> float:
        return (self.t_next_us - self.t_last_us) * 1e-6


def merge_gaps(gaps: list[EventGap]) -> list[EventGap]:
    """Overlapping gaps (the events and the IMU of a paused recorder) joined, in time order."""
    out: list[EventGap] = []
    for g in sorted(gaps, key=lambda g: (g.t_last_us, g.t_next_us)):
        if out and g.t_last_us <= out[-1].t_next_us:
            p = out[-1]
            stream = p.stream if g.stream == p.stream else "events or IMU samples"
            out[-1] = EventGap(p.t_last_us, max(p.t_next_us, g.t_next_us), stream)
        else:
            out.append(g)
    return out


def find_gaps(t: np.ndarray, longer_than_us: int, after_us: int, stream: str = "events") -> list[EventGap]:
    """The gaps longer than ``longer_than_us`` between consecutive timestamps ``t`` that end after ``after_us``."""
    gaps = []
    n = int(t.shape[0])
    for i0 in range(0, max(n - 1, 0), _CHUNK):
        i1 = min(i0 + _CHUNK + 1, n)
        d = np.diff(t[i0:i1])
        for j in np.flatnonzero(d > longer_than_us):
            a, b = int(t[i0 + j]), int(t[i0 + j + 1])
            if b > after_us:
                gaps.append(EventGap(a, b, stream))
    return gaps
