"""Columnar event arrays: ``t`` int64 microseconds, ``x``/``y`` uint16, ``p`` int8 (+1 ON / -1 OFF)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.errors import InputError

EVENT_DTYPES = {"t": np.int64, "x": np.uint16, "y": np.uint16, "p": np.int8}
MAX_SPAN_US = (1 << 27) * 1000
"""Longest span of one recording's events, microseconds (~37 hours, what the evpose HDF5 millisecond index holds):
beyond it a timestamp is wrong, and one stray far-future event made `evpose track` run updates through empty time."""


def check_span(t: np.ndarray, source, offset: int = 0, t_first: int | None = None) -> None:
    """Raise :class:`InputError` naming the first event more than :data:`MAX_SPAN_US` after the first one
    (``t_first``, default ``t[0]``; ``offset``: global index of ``t[0]``)."""
    if not len(t):
        return
    t0 = int(t[0]) if t_first is None else int(t_first)
    if int(t[-1]) - t0 > MAX_SPAN_US:
        i = int(np.argmax(t - t0 > MAX_SPAN_US))
        raise InputError(source, f"events span {(int(t[-1]) - t0) / 3.6e9:.1f} hours (from {t0} to {int(t[-1])} us); timestamps look wrong", f"event {offset + i}")


@dataclass(frozen=True)
class EventArray:
    """A time-sorted batch of events, stored column by column.

    Columns are plain numpy arrays so numba kernels and h5py take them without
    copies. Construct through :meth:`from_arrays` to get dtype conversion and
    shape checks; the raw constructor trusts its caller.
    """

    t: np.ndarray
    """Timestamps, int64 microseconds, non-decreasing."""
    x: np.ndarray
    """Column of the pixel, uint16, 0 at the left."""
    y: np.ndarray
    """Row of the pixel, uint16, 0 at the top."""
    p: np.ndarray
    """Polarity, int8, +1 brighter (ON) / -1 darker (OFF)."""

    @classmethod
    def from_arrays(cls, t, x, y, p) -> "EventArray":
        """Convert columns to the canonical dtypes; ``p`` may be 0/1, bool or -1/+1."""
        t = np.ascontiguousarray(t, dtype=np.int64)
        x = np.ascontiguousarray(x, dtype=np.uint16)
        y = np.ascontiguousarray(y, dtype=np.uint16)
        p = np.asarray(p)
        if p.dtype == np.bool_ or (p.size and p.min() >= 0):
            p = np.where(p.astype(np.int8) > 0, 1, -1).astype(np.int8)
        else:
            p = np.ascontiguousarray(p, dtype=np.int8)
        n = t.shape[0]
        if not (t.ndim == x.ndim == y.ndim == p.ndim == 1) or not (x.shape[0] == y.shape[0] == p.shape[0] == n):
            raise ValueError(f"event columns must be 1-D of equal length, got {t.shape} {x.shape} {y.shape} {p.shape}")
        return cls(t, x, y, p)

    @classmethod
    def empty(cls) -> "EventArray":
        return cls.from_arrays(np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int8))

    @classmethod
    def concatenate(cls, parts: list["EventArray"]) -> "EventArray":
        if not parts:
            return cls.empty()
        return cls(*(np.concatenate([getattr(e, c) for e in parts]) for c in "txyp"))

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __getitem__(self, index) -> "EventArray":
        """Slice or boolean/integer mask; always returns an EventArray."""
        return EventArray(self.t[index], self.x[index], self.y[index], self.p[index])

    @property
    def duration_us(self) -> int:
        return int(self.t[-1] - self.t[0]) if len(self) else 0

    def index_range(self, t0_us: int, t1_us: int) -> tuple[int, int]:
        """Indices ``[i0, i1)`` of events with ``t0 <= t < t1`` (binary search, needs sorted ``t``)."""
        i0 = int(np.searchsorted(self.t, t0_us, side="left"))
        i1 = int(np.searchsorted(self.t, t1_us, side="left"))
        return i0, i1

    def time_window(self, t0_us: int, t1_us: int) -> "EventArray":
        """Events with ``t0 <= t < t1`` as views into this array."""
        i0, i1 = self.index_range(t0_us, t1_us)
        return self[i0:i1]

    def validate(self, width: int | None = None, height: int | None = None, source: str | None = None) -> None:
        """Raise :class:`InputError` naming the first offending event (sortedness, bounds, polarity)."""
        if len(self) == 0:
            return
        dt = np.diff(self.t)
        bad = np.flatnonzero(dt < 0)
        if bad.size:
            i = int(bad[0]) + 1
            raise InputError(source, f"timestamp {int(self.t[i])} us is earlier than the previous {int(self.t[i - 1])} us (timestamps must be sorted)", f"event {i}")
        if width is not None:
            bad = np.flatnonzero(self.x >= width)
            if bad.size:
                i = int(bad[0])
                raise InputError(source, f"x={int(self.x[i])} is outside the sensor width {width}", f"event {i}")
        if height is not None:
            bad = np.flatnonzero(self.y >= height)
            if bad.size:
                i = int(bad[0])
                raise InputError(source, f"y={int(self.y[i])} is outside the sensor height {height}", f"event {i}")
        bad = np.flatnonzero((self.p != 1) & (self.p != -1))
        if bad.size:
            i = int(bad[0])
            raise InputError(source, f"polarity {int(self.p[i])} is not +1/-1", f"event {i}")
