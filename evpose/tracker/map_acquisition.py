"""Whether a map fits a recording at all: the rule behind ``evpose track --acquire-s`` and the viewer's warning.

A map of another scene, or of this scene in another frame, does not make the
tracker fail loudly: it coasts on the motion model and marks its poses
DEGRADED, update after update, each with a plausible reason. What gives such
a pairing away is that not one update registers against the map from the start
on, for longer than a correct map ever takes (the bundled recordings register
from their first update). The CLI stops with an error then; the viewer, which
must keep showing what the tracker sees, warns.

Two rules, both over the first ``acquire_s`` seconds: (1) not one update registers; (2) the registrations are no
better than chance (:func:`chance_mismatch`; the tracker counts the chance level only within the window its caller
sets, ``Tracker.chance_until_us``: ``evpose track`` the ``--acquire-s`` window, the viewer's engine the first
second, which ``app --prepare`` reads whatever its ``--acquire-s``).

Why rule 1 alone is not enough, measured (session 19; /tmp/s19/qa19b/measure.py, measure_seeds.py and
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

A wrong map registers by chance wherever events cover the image densely enough for the tracker's acceptance
(``registration.min_inlier_ratio``): under flicker (0.63-0.84 of the updates, from the first one), in a textured
scene (0.47-0.81), with moving objects, and elsewhere from update 7-121 on; a right map can lose registration early
(indoor at 240x180: from 0.6 s on, all four seeds). So rule 1 catches 19 of the 70 wrong pairings and none of the
right ones.

Rule 2 compares each update's inlier count with its chance level (:mod:`evpose.tracker.chance_level`: the share of
the registered points displaced 4 px in eight directions that still read below the inlier threshold) as a binomial
z-score (:func:`chance_z`), and takes the best median over 20 consecutive updates of the window
(:func:`chance_evidence`); excess: the median of inlier share minus chance level. Same 140 pairings, first second
(/tmp/s19/wrongmap19/measure.py, stats.py, stats2.py):

========================  =====  ===========  ===========  ===========  ==========  ===========  ===========
group                     runs   best 20-upd  best 20-upd  median z     median z    excess       excess
                          R / W  z, right     z, wrong     right        wrong       right        wrong
========================  =====  ===========  ===========  ===========  ==========  ===========  ===========
landing, slow, fast,      36/36  20.3 - 29.6  2.4 - 9.4    19.1 - 24.8  0.0 - 6.1   0.22 - 0.39  0.00 - 0.07
rotation, hdr, noisy
indoor (seeds 0-3)        12/12  24.2 - 48.1  1.3 - 3.4    16.1 - 21.7  0.0 - 2.2   0.04 - 0.22  0.00 - 0.01
dynamic                   6/6    20.9 - 27.4  4.6 - 12.9   17.7 - 23.0  1.8 - 9.7   0.24 - 0.33  0.01 - 0.14
flicker                   6/6    19.7 - 26.0  3.5 - 11.4   17.4 - 22.6  2.1 - 6.6   0.26 - 0.34  0.04 - 0.21
texture                   6/6    21.8 - 25.6  5.0 - 7.5    20.6 - 22.3  3.2 - 4.9   0.28 - 0.33  0.02 - 0.07
demo recordings           4/4    24.9 - 46.1  2.9 - 7.1    19.7 - 21.5  0.0 - 4.2   0.12 - 0.22  0.00 - 0.02
all                       70/70  19.7 - 48.1  1.3 - 12.9   16.1 - 24.8  0.0 - 9.7   0.04 - 0.39  0.00 - 0.21
========================  =====  ===========  ===========  ===========  ==========  ===========  ===========

The z-scores separate every group, the raw excess over chance does not (indoor's right 0.04 against flicker's wrong
0.21), nor the inlier share / chance ratio (right 2.4-5.0, wrong 0.0-4.3). The best 20-update run is kept over the
window's median (which separates as well, 16.1 against 9.7) because the median of a right map that loses the track
after 0.6 s (indoor 240x180) sits on the edge of its good half. With ``min_chance_z`` 16 the two rules refuse all
70 wrong pairings and none of the right ones; the margin is 1.23x either side (the wrong dynamic 0.3 s run at 12.9:
its registrations in the first 0.1 s; the right flicker 346x260 0.5 s run at 19.7). Separating less (first second):
the same z over a 10 px ring (best runs right 26.0-113.8, wrong 2.3-20.9: 1.24x; window medians 19.6 against 15.6);
not at all: the share of the field's box below the threshold as the chance level (share / chance: right 9.7-33.9,
wrong 0.0-103.4), and the 4 px z over the first 5 updates alone (median right 10.2-27.9, wrong -0.4-10.9).
Limits: z grows with the number of points in view (the right maps here have ~200-800 in the image), so a small map
scores lower; under extreme noise a right map is refused too (best-run z of the right / an edgeless wrong map,
synthetic scenes of the tests: the box of ``tests/tracker``, 240x180 ``stpe``, 45 / - at 2e4 noise events/s, 23 / 0.9
at 2e6, 0.6 / - at 6e6; the squares of ``tests/app``, 160x120 ``full``, 36.0 / 2.4 at none, 31.5 / 5.1 at 5e5,
20.3 / 7.6 at 1e6, 11.6 / 7.3 at 2e6; /tmp/s19/wrongmap19/probe.py, probe_app.py). ``--acquire-s 0`` turns both rules
off. Cost: the chance count takes 0.09 ms (median; p99 0.15 ms) of a 3.8 ms update on the landing demo, only within
the window (/tmp/s19/wrongmap19/cost.py, thread CPU time).
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
    return float(np.median(np.lib.stride_tricks.sliding_window_view(z, k), axis=1).max())


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
            f" chance level, need {cfg.min_chance_z:g}): is it this recording's map, in its frame?"
            " (--acquire-s 0 skips this check)")
