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
from dataclasses import dataclass, field

import numpy as np

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


@dataclass
class MapAcquisitionConfig:
    """The chance-level test of the acquisition window (see the module docstring)."""

    min_chance_z: float = field(default=16.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """Least map evidence over the acquisition window (:func:`chance_evidence`) a map must show, binomial standard
    deviations of the inlier count above its chance level (0 = off). Measured over the first second of 140 pairings:
    right maps 19.7-48.1, wrong maps 1.3-12.9; 16 sits at about their geometric mean (1.23x from either side)."""
    run_updates: int = field(default=20, metadata={"min": 1, "max": 1000, "step": 1, "unit": "updates"})
    """Consecutive updates (0.1 s at 200 Hz) whose median z-score counts: the best such run is the map's evidence, so a
    right map that loses the track after a good start (indoor at 240x180 from 0.6 s on) still passes, updates."""


def chance_z(counts: Mapping[str, int]) -> float | None:
    """One update's inlier count above its chance level (``chance_hits / chance_samples``,
    :mod:`evpose.tracker.chance_level`) in binomial standard deviations (at least one point's); None without the
    counts (updates past the window, older caches)."""
    samples = counts.get("chance_samples")
    if samples is None:
        return None
    n = max(int(counts.get("points_in_image", 0)), 1)
    p = int(counts.get("chance_hits", 0)) / max(int(samples), 1)
    return (int(counts.get("inliers", 0)) - n * p) / float(np.sqrt(max(n * p * (1.0 - p), 1.0)))


def chance_evidence(steps: Iterable[tuple[int, Mapping[str, int]]], run_updates: int = 20) -> float | None:
    """The best median :func:`chance_z` over ``run_updates`` consecutive ``steps`` (all of them when fewer) that
    carry the chance counts; None when none do."""
    z = np.array([v for v in (chance_z(c) for _, c in steps) if v is not None], dtype=np.float64)
    if z.size == 0:
        return None
    k = min(max(int(run_updates), 1), z.size)
    return float(max(np.median(z[i:i + k]) for i in range(z.size - k + 1)))


def chance_mismatch(steps: Iterable[tuple[int, Mapping[str, int]]], t0_us: int, acquire_s: float = DEFAULT_ACQUIRE_S,
                    finished: bool = False, config: MapAcquisitionConfig | None = None) -> float | None:
    """The map evidence of the steps within ``acquire_s`` of ``t0_us`` once they span it (or ``finished``: the
    recording ends sooner) when it stays below ``config.min_chance_z``, else None (also when off, ``acquire_s <= 0``,
    or no step carries the chance counts)."""
    cfg = config if config is not None else MapAcquisitionConfig()
    if acquire_s <= 0 or cfg.min_chance_z <= 0:
        return None
    steps = [(int(t), c) for t, c in steps]
    if not steps or not (finished or (steps[-1][0] - int(t0_us)) * 1e-6 >= acquire_s - 1e-9):
        return None
    window = [(t, c) for t, c in steps if (t - int(t0_us)) * 1e-6 <= acquire_s + 1e-9]
    z = chance_evidence(window, cfg.run_updates)
    return z if z is not None and z < cfg.min_chance_z else None


def chance_problem(evidence: float, seconds: float, recording_name: str, config: MapAcquisitionConfig | None = None) -> str:
    """The one-line problem for a map :func:`chance_mismatch` flags."""
    cfg = config if config is not None else MapAcquisitionConfig()
    return (f"this map's points lie on recent events hardly more often than chance in the first {seconds:.2f} s of"
            f" {recording_name} (best {cfg.run_updates}-update median {evidence:.1f} standard deviations above the"
            f" chance level, need {cfg.min_chance_z:g}): is it this recording's map, in its frame?")
