"""Whether a map fits a recording at all: the rule behind ``evpose track --acquire-s`` and the viewer's warning.

A map of another scene, or of this scene in another frame, does not make the
tracker fail loudly: it coasts on the motion model and marks its poses
DEGRADED, update after update, each with a plausible reason. What gives such
a pairing away is that not one update registers against the map from the start
on, for longer than a correct map ever takes (the bundled recordings register
from their first update). The CLI stops with an error then; the viewer, which
must keep showing what the tracker sees, warns.

Why the rule stays "none registered", measured (session 19; /tmp/s19/qa19b/measure.py, measure_seeds.py and
summary.py): ten ``evpose simulate`` scenarios (seed 0) at 240x180 and 346x260 for 0.3, 0.5 and 1 s, indoor
also with seeds 1-3 for 1 s, and the four demo recordings, each tracked from ground truth with
``maps/landing_map.ply`` and ``maps/indoor_map.ply`` (70 right and 70 wrong pairings); over each run's first
second (or all of it):

==============================================  ===========  ===========
statistic                                       right map    wrong map
==============================================  ===========  ===========
share of the updates that registered            0.49 - 1.00  0.00 - 0.84
median inlier share of the registered updates   0.15 - 0.55  0.00 - 0.86
median inlier share of the first 5 updates      0.19 - 0.55  0.00 - 0.82
first update that registered                    always 1st   1st - never
==============================================  ===========  ===========

No threshold on any of them separates the two, so none is applied. A wrong map registers by chance wherever
events cover the image densely enough for the tracker's acceptance (``registration.min_inlier_ratio``: 10 % of
the map points used on recent events): under flicker (0.63-0.84 of the updates, from the first one), in a
textured scene (0.47-0.81), with moving objects (from the first update in the 0.3 s runs), and elsewhere from
update 7-121 on; a right map can lose registration early (indoor at 240x180: 0.49-0.50 of its first second, all
four seeds). So the rule catches 19 of the 70 wrong pairings (every demo recording with the other map; indoor
with the landing map; three landing runs), none of the right ones, and lets through e.g. a 0.3 s 240x180 landing
with ``indoor_map.ply`` (updates 16-44 of 53 register). A share threshold below the right maps' 0.49 would catch
more without a false alarm in these runs (share < 0.25: 39 of 70; < 0.4: 47), but with no margin to speak of
against a right map losing track half way through the window it is not applied. Separating them would take
comparing the inlier share with the chance level set by how much of the image the recent events cover, which the
tracker does not count.
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
