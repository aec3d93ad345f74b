"""Consistency (background-activity) noise filter: keep an event if one of its 8 neighbours fired within ``T`` before it.

EV-Pose section IV-A. State is one last-timestamp map over the sensor, padded by
one pixel on every side so the per-event neighbour test needs no bounds checks.
Every event (kept or not) updates its own pixel, as in the classic filter: a
second noise event next to a first one within ``T`` is kept, which is the price of
O(1) work per event.

Not kept (session 12, demo batches of 600 events, same keep-masks): reading the map through a flat view at one
unsigned offset per event (what sped up the polarity filter's kernels) took 4.8 -> 5.6 us per batch, slower.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.core.events import EventArray

NEVER_US = np.int64(-(2**62))
"""Timestamp of a pixel that has never fired (far enough in the past that no window reaches it)."""


@dataclass
class NoiseFilterConfig:
    """Consistency noise filter settings."""

    enabled: bool = True
    """Run the filter; when off every event is kept."""
    window_us: int = field(default=5000, metadata={"min": 100, "max": 100000, "step": 100, "unit": "us"})
    """Window ``T``: an event is kept if a neighbour fired at most this long before it, microseconds."""


@nb.njit(cache=True)
def _filter_kernel(t, x, y, last, window_us, enabled, keep):
    """Per event: test the 8 neighbours of the padded map, then stamp the own pixel. Returns the kept count."""
    n = t.shape[0]
    kept = 0
    for i in range(n):
        ti = t[i]
        r = np.int64(y[i]) + 1
        c = np.int64(x[i]) + 1
        lim = ti - window_us
        # Unrolled 8-neighbour max: branch-free loads keep the loop fast.
        m = last[r - 1, c - 1]
        v = last[r - 1, c]
        if v > m:
            m = v
        v = last[r - 1, c + 1]
        if v > m:
            m = v
        v = last[r, c - 1]
        if v > m:
            m = v
        v = last[r, c + 1]
        if v > m:
            m = v
        v = last[r + 1, c - 1]
        if v > m:
            m = v
        v = last[r + 1, c]
        if v > m:
            m = v
        v = last[r + 1, c + 1]
        if v > m:
            m = v
        k = (m >= lim) or not enabled
        keep[i] = k
        kept += k
        last[r, c] = ti
    return kept


class ConsistencyNoiseFilter:
    """Stateful 8-neighbour recency filter over a ``width`` x ``height`` sensor."""

    def __init__(self, config: NoiseFilterConfig, width: int, height: int):
        self.config = config
        self.width = int(width)
        self.height = int(height)
        self._last = np.full((self.height + 2, self.width + 2), NEVER_US, dtype=np.int64)

    def filter(self, events: EventArray) -> np.ndarray:
        """Keep-mask (bool, one per event) for a time-sorted batch; updates the state with every event."""
        n = len(events)
        keep = np.empty(n, dtype=np.bool_)
        if n == 0:
            return keep
        # When disabled the kernel still stamps pixels, so switching the filter on mid-run
        # behaves as if it had always run.
        _filter_kernel(events.t, events.x, events.y, self._last, np.int64(self.config.window_us), bool(self.config.enabled), keep)
        return keep

    @property
    def last_timestamps(self) -> np.ndarray:
        """Last event time per sensor pixel, int64 (H, W) microseconds (view; ``NEVER_US`` if none)."""
        return self._last[1:-1, 1:-1]

    def reset(self) -> None:
        self._last.fill(NEVER_US)

    def snapshot(self) -> dict:
        return {"last": self._last.copy()}

    def restore(self, state: dict) -> None:
        np.copyto(self._last, state["last"])
