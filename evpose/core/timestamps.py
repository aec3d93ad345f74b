"""Checks and look-ups shared by the time-stamped sample series of :mod:`evpose.core` (IMU samples, trajectories)."""

from __future__ import annotations

import numpy as np

from evpose.errors import InputError


def window_slice(t: np.ndarray, t0_us: int, t1_us: int) -> slice:
    """Index range of the sorted stamps ``t`` in ``[t0_us, t1_us)``."""
    return slice(int(np.searchsorted(t, t0_us, side="left")), int(np.searchsorted(t, t1_us, side="left")))


def check_series(t: np.ndarray, finite: np.ndarray, source: str | None, record: str) -> None:
    """Raise :class:`InputError` naming the first ``record`` (e.g. ``"pose"``) whose stamp does not increase or whose
    values are not finite (``finite``: one flag per record)."""
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(source, f"timestamp {int(t[i])} us does not increase (previous {int(t[i - 1])} us)", f"{record} {i}")
    bad = np.flatnonzero(~finite)
    if bad.size:
        raise InputError(source, "NaN or infinite value", f"{record} {int(bad[0])}")
