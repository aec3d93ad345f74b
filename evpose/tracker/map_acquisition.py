"""Whether a map fits a recording at all: the rule behind ``evpose track --acquire-s`` and the viewer's warning.

A map of another scene, or of this scene in another frame, does not make the
tracker fail loudly: it coasts on the motion model and marks its poses
DEGRADED, update after update, each with a plausible reason. What gives such
a pairing away is that not one update registers against the map from the start
on, for longer than a correct map ever takes (the bundled recordings register
from their first update). The CLI stops with an error then; the viewer, which
must keep showing what the tracker sees, warns.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

DEFAULT_ACQUIRE_S = 1.0
"""Seconds from the start within which some update must register, seconds (``evpose track --acquire-s``'s default)."""


def registered(counts: Mapping[str, int]) -> bool:
    """Whether one update registered against the map (steps without the count, e.g. from older caches, did)."""
    return bool(counts.get("registered", 1))


def unacquired_s(steps: Iterable[tuple[int, Mapping[str, int]]], t0_us: int) -> float | None:
    """Seconds from ``t0_us`` to the last of ``steps`` (``(t_us, counts)`` from the first update on, in order) when
    none of them registered; None as soon as one did (or when there are none)."""
    last = None
    for t_us, counts in steps:
        if registered(counts):
            return None
        last = t_us
    return None if last is None else (int(last) - int(t0_us)) * 1e-6


def map_mismatch(steps: Iterable[tuple[int, Mapping[str, int]]], t0_us: int, acquire_s: float = DEFAULT_ACQUIRE_S,
                 finished: bool = False) -> float | None:
    """The seconds without a registration when they reach ``acquire_s`` (the map does not look like this
    recording's), else None. ``finished``: ``steps`` are all the recording has, so a recording shorter than
    ``acquire_s`` that never registered is reported too (as ``evpose track`` does). ``acquire_s <= 0`` never reports."""
    if acquire_s <= 0:
        return None
    s = unacquired_s(steps, t0_us)
    return s if s is not None and (s >= acquire_s or finished) else None


def mismatch_problem(seconds: float, recording_name: str, reason: str = "") -> str:
    """The one-line problem every command reports for a map :func:`map_mismatch` flags (``reason``: the last
    update's, in parentheses when given)."""
    why = f" ({reason})" if reason else ""
    return (f"no update registered against this map in the first {seconds:.2f} s of {recording_name}{why}:"
            " is it this recording's map, in its frame?")
