"""Per-point event leads from how many events each pixel passage of the point's edge fires (issue 7, session 35).

Physics (ESIM, :mod:`evpose.sim.esim`; any DVS-like pixel): a pixel fires when its log intensity has moved a
threshold ``C`` from its reference, which then steps by ``C``. An edge of log contrast ``D`` sweeping a pixel moves
the pixel's area-weighted log intensity along a concave curve of its coverage (``log((1 - f) e^L0 + f e^L1)``), and
the reference carries over from the pixel's previous passage: after an opposite-polarity passage the first event
needs ``C``-``2C`` of change, after a same-polarity one ``0``-``C``. So the events of a passage sit at log levels
``[a, D]`` of the transition (``a`` the carried-over gap), and where the edge is when they fire, hence each point's
mean event lead along the motion, depends on ``D / C`` and the history, not on the point's class alone.
:func:`coverage_lead` is that model (events uniform in log level over ``[lo, hi]`` of the transition, the pixel
sampled by the renderer's ``s x s`` n-rooks pattern); on a synthetic edge through the simulator's ESIM it gives the
simulated mean lead within 0.07 px for contrasts 0.5-3 at edges 0.3 and 0.8 rad off the pixel rows
(``/tmp/s35/lead35/synth.py``; up to 0.11 px on an axis-aligned one, whose renders there step in phase with the pixels).

Measured (session 35, ``/tmp/s35/lead35``: ``decomp.py`` oracle dumps at the true pose against the map snapped onto
the true edges, ``contrast.py`` the rendered contrast per point, ``hist.py`` each event's pixel history, ``ana2-4.py``;
240x180 landing seeds 0 / 1; groups = a point's events of one polarity and motion sign, >= 10 events, the 'beyond'
class left out): the model with the rendered contrast and each event's pixel history explains 0.60 / 0.59 of the
groups' mean-lead variance on the 2 s flight (the class leads 0.58 / 0.53, with no parameter fitted) but only 0.21 /
0.22 on the 3 s one (class leads 0.38 / -0.14); of what the class leads leave, the true contrast explains 0.06-0.10
(2 s) / 0.21-0.23 (3 s). The best single online-observable predictor of what they leave is the events per passage:
groups whose pixels fire one event per passage (events / passage-starting events < 1.15, a quarter of the groups) sit
-0.033 px (2 s) / -0.096 px (3 s) from their class lead, the others +0.00 to +0.04 (both polarities alike; ``ana4.py``): a
barely-crossed threshold fires late in the transition. This module counts that ratio online per map point and adds
``ContrastLeadConfig.lone_lead_px`` (since session 43 ``lone_on_lead_px`` / ``lone_off_lead_px``) to both leads of
the points whose ratio says "one event per passage" (online, at the end of seed 0's 2 s flight, it flags 19 % of the
counted points, the whole-flight offline count 18 %, agreeing on 90 %; ``online.py``).

Session 34's multiplicity proxy (``/tmp/s34/rim34/mult.py``: events per update times ``Z / |v|``) was inconclusive
because it does not measure multiplicity: on these dumps it is uncorrelated with the events per passage (+0.00 to
+0.05) and is mostly ``Z / |v|``; it was also read against the built map, whose points' own errors add to these offsets
(the snapped map here takes them out). What ``Z / |v|`` does pick up is a lag growing with the edge's normal speed (``delay.py``: regressed per
event, 0.31-0.39 ms for ON, 0.02-0.30 ms for OFF on both flights; the fusion twist's speed error is < 3 %), which
correlates with the 3 s flight's per-window OFF offsets (-0.40 with ``log |v|``) but not the 2 s one's. The feet of
vertical faces (whose covered-foot lead flips between the flights): their OFF groups sit +0.03 / +0.10 px (ground /
face side) from their class leads on the 2 s flight and -0.08 / +0.01 on the 3 s one; the contrast + history model
has the sign on both but not the size (``feet.py``).

Session 38 (``/tmp/s38/tr38``: ``exmodel.py``, ``resid.py``, ``ana.py``): the coverage model per (point, polarity,
motion sign) group from the events per passage (``|D| = C E/X``) instead of the rendered contrast predicts what the
class leads leave nearly as well (correlation 0.31 / 0.34 against 0.35 / 0.38 on the 2 s flight's seeds 0 / 1, 0.63 /
0.75 against 0.65 / 0.76 on the 3 s one). But only its mean per (polarity, class) moves the registrations' slow
tilt-vs-sideways bias at the true pose (events against the tracker's learned map, slow part 2.61 / 3.25 -> 2.46 /
2.53 mm, 2 s seeds 0 / 1), which is a class lead shift; with that mean taken out the per-point spread changes it by
nothing (2.64 / 3.30; 3 s 3.34 / 1.97 -> 3.32 / 2.01 mm), even on the 3 s flight, where it still correlates 0.54 /
0.40 per point with what the events leave against their learned map (2 s: -0.24 / -0.03): the contrast's offsets within
a class hardly project on the pose (the events' learned offsets take up the rest, :mod:`evpose.tracker.event_registration`).

Session 42 (``/tmp/s42/lag42``, issue 7's other flights, ``evpose simulate --flight N``): on flights 2 and 9 one such
edge sets the shift-x / tilt-about-y ridge of registrations started from the true pose. A 4 m building's foot beside
the 1 m box the flights pass over (rendered log levels -1.300 / -0.801: contrast 0.50 against ESIM's 0.40) fires one
ON event per passage, about three quarters through the transition (the coverage model: -0.26 px), and its raw events
sit -0.27 / -0.31 px along its motion against its -0.07 lead, while the box's rims sit +0.03 to +0.09 px beyond
theirs; left out of the map (an oracle), the ridge from the truth over 0.25-1.25 s goes from -9.5 mm / +145 mdeg to
-2.2 / +32 (flight 2) and from -11.9 / +179 to -0.5 / +10 (flight 9). Every one of its points counts a ratio of 1.0,
but the built map holds a point every few millimetres, so each had only a median 3.9 counted events at 0.8 s and 4 %
of them passed ``min_events``: hence ``pool_radius_m``, which sums the counts of the parallel neighbours. The ridge
from the truth (``ridge.py`` on ``oracle.py`` runs): ``lone_lead_px`` -0.2 alone -9.3 / +136 and -11.8 / +166 (flight
9), with ``min_events`` 3 -7.2 / +100 and -8.5 / +114, pooled over 5 cm -4.9 / +64 and -7.5 / +98; the defaults
(-0.1, pooled) -7.0 / +102 and -9.8 / +139. Closed loop: see ``ContrastLeadConfig.lone_on_lead_px``. What is left: the
lead was one number for every lone point, where the coverage model gives -0.26 px for this foot and about -0.03 on the
nominal flight's lone points.

Session 43 (``/tmp/s43/lead43``: ``evdump.py`` dumps every associated event of oracle runs, each registration from the
true pose, with its offset along its point's image motion at the truth; ``ana.py`` / ``ana2.py`` / ``ana3.py``; lone =
the pooled whole-run ratio < 1.15 with >= 10 events; px beyond the class leads): what separates the lone points whose
events trail from those that do not is their polarity, not the point. Lone ON events sit -0.22 / -0.15 / +0.03 px
(240x180 flights 2 / 9 / 1) and -0.18 / -0.16 / -0.20 (nominal seeds 0 / 1 / 2) against the other ON events' +0.02 /
+0.05 / +0.04 and 0.00 / -0.00 / -0.00: they trail by 0.16-0.24 px on both (flight 1 -0.01). Lone OFF events sit -0.19 /
-0.35 / -0.12 and -0.04 / -0.06 / -0.05 against the other OFF events' -0.22 / -0.19 / -0.16 and -0.15 / -0.15 / -0.13:
nothing common (+0.03 / -0.17 / +0.04, +0.11 / +0.09 / +0.09). (Session 35's "both polarities alike" was read against
the map snapped onto the true edges, these against the built map the tracker registers.) The foot's events are all ON,
the nominal flight's lone events 91-94 % OFF (the flights' other lone events 58-85 % OFF), so one lead for both
polarities over-corrected the nominal flight. Hence ``lone_on_lead_px`` / ``lone_off_lead_px``. Per-point observables
did not separate them: the share of a point's passage-starting events whose pixel had never fired (foot 0.94 / 0.83, the
nominal flight's lone points 0.43 / 0.42 / 0.38, the flights' other lone points 0.52 / 0.45; by its terciles the other
lone points trail less the higher it is, the opposite of the foot), the normal image speed (by terciles no common
order), the events per swept pixel (the pool's events over its extent times ``|v|`` times the update window: too noisy
to read a contrast from). Nor can the counts give :func:`coverage_lead` a per-point contrast: a fresh passage (reference
reset, the first event at ``C``) of any ``D`` in ``[C, 2C)`` fires exactly one event, while its lead runs from -0.64 px
(ON, ``D`` = 1.05 ``C``) through -0.29 (the foot's 1.25 ``C``) to +0.11 (2 ``C``); what would tell them apart is the
events' timing, i.e. the residual the learned offsets already take. Closed loop: ``ContrastLeadConfig.lone_on_lead_px``
(ON -0.2 with OFF -0.05 is better on every set of runs, the nominal flight's included, though not on two of the three
bundled demos: the default since session 43). What is left: in the third second of the demo ``landing`` (normal image speed median 214 px/s) 54 % of the ON
events count as lone and they do not trail (+0.04 px; ``ana4.py``, the passage start at 4 crossings instead of 2 the
same); why the flag loses its meaning there is not known.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np
from scipy.spatial import cKDTree


@dataclass
class ContrastLeadConfig:
    """Lead of the map points whose pixels fire one event per passage of their edge (see the module)."""

    lone_on_lead_px: float = field(default=-0.2, metadata={"min": -1.0, "max": 1.0, "step": 0.01, "unit": "px"})
    """Added to the ON lead of a point whose events come one per pixel passage (``lone_max_ratio``), pixels
    (negative = behind the edge along its motion; 0 = off; its OFF lead takes ``lone_off_lead_px``; before session 43
    one field, ``lone_lead_px``, set both). The oracle dumps put those points (a quarter of the groups, 15-21 % of the
    events) -0.03 (2 s) / -0.08 to -0.11 px (3 s landing, 240x180) from their class leads, the others +0.00 / +0.01 (``/tmp/s35/lead35/ana5.py``; of the variance the class leads leave this explains 4-5 % on
    the 2 s flight, 14-22 % on the 3 s one).

    Off: it helps the 3 s flight only (``full`` from ground truth, the CLI path on the cached landings, paired against
    main's defaults, mean ATE RMSE mm +- standard error, seeds better; ``/tmp/s35/lead35/run.sh``, ``cmp.py``):
    -0.05: 240x180 2 s seeds 0-23 5.255 -> 5.259 (+0.004 +- 0.045, 11 of 24), held-out 24-47 5.652 -> 5.622 (-0.030 +-
    0.043, 13 of 24), 3 s seeds 0-7 13.512 -> 13.201 (-0.31 +- 0.24, 6 of 8), 346x260 seeds 0-23 4.279 -> 4.312
    (+0.033 +- 0.052, 9 of 24); -0.08: 5.317 (+0.062 +- 0.046, 10 of 24), 5.618 (-0.034 +- 0.057, 15 of 24), 12.895
    (-0.62 +- 0.27, 7 of 8), 346x260 4.350 (+0.071 +- 0.082, 8 of 24). The rotation error falls in every set (ARE
    0.0603 -> 0.0579 / 0.0565, 0.0629 -> 0.0605 / 0.0594, 0.1113 -> 0.1108 / 0.1096, 346x260 0.0504 -> 0.0480 /
    0.0473 deg).

    On since session 42 at -0.1 with ``pool_radius_m`` 0.05, for the other flights (``evpose simulate --flight N``;
    the module has why; ``/tmp/s42/lag42``: ``runset.sh``, ``sets.py``; ``full`` from ground truth, the CLI path on
    ``/tmp/s41/data/track``, paired against main's defaults of session 41, mean ATE RMSE mm +- standard error, runs
    better, ARE deg). -0.1 pooled: 240x180 flights 1-12 (tuning) 14.187 -> 12.126 (-2.06 +- 0.57, 9 of 12), ARE 0.1885
    -> 0.1597; held-out flights 13-24 14.906 -> 13.798 (-1.11 +- 0.43, 10 of 12), ARE 0.1741 -> 0.1608; 346x260 flights
    1-12 and 15 12.956 -> 11.198 (-1.76 +- 0.40, 12 of 13), ARE 0.1836 -> 0.1569; the nominal flight, seeds 0-23 (the
    path sessions 12-40 tuned on) 4.770 -> 4.922 (+0.15 +- 0.16, 10 of 24), ARE 0.0588 -> 0.0562. The lead, same path: nominal
    346x260 seeds 0-23 4.144 -> 4.204 (+0.059 +- 0.118, 10 of 24), 240x180 24-35 5.419 -> 5.292 (-0.127 +- 0.246, 6 of
    12). -0.2 pooled:
    14.187 -> 10.629 (-3.56 +- 1.23, 7 of 12), ARE 0.1381; 14.906 -> 13.074 (-1.83 +- 0.77, 10 of 12); 12.956 -> 9.091
    (-3.87 +- 0.94, 12 of 13), ARE 0.1271; but nominal 4.770 -> 5.802 (+1.03 +- 0.28, 6 of 24), ARE 0.0588 -> 0.0709.
    -0.2 unpooled with ``min_events`` 3: flights 1-12 11.474 (-2.71 +- 0.96, 8 of 12). The bundled demos (346x260,
    4 s, the nominal spiral) with -0.1 pooled: ``landing`` 6.554 -> 7.530 mm (ARE 0.058 -> 0.076 deg), ``landing_fast``
    9.035 -> 8.718, ``landing_dynamic`` 6.012 -> 7.748 (``demo.sh``): the nominal flight's lone points sit only -0.03
    px from their class leads (session 35), so there the lead over-corrects; 0 restores session 41's outputs bit for
    bit. CPU of a whole ``evpose track`` (240x180 flight 2, 3 alternated runs each, ``cpu.sh``): 5.00 s off, 5.06 s on
    (user; noise +-0.5 s).

    Per polarity since session 43 (the module has why: lone ON events trail the other ON events by 0.16-0.24 px on the
    flights and the nominal flight alike, lone OFF events do not; ``/tmp/s43/lead43``: ``sets.sh``, ``sets.py``,
    ``demo.sh``; ``full`` from ground truth, the CLI path on ``/tmp/s41/data/track``, paired against main 29e1c44 =
    -0.1 / -0.1, mean ATE RMSE mm +- standard error, runs better, ARE deg). ON -0.2, OFF -0.05: 240x180 flights 1-12
    (tuning) 12.126 -> 10.949 (-1.18 +- 0.41, 9 of 12), ARE 0.1597 -> 0.1429; held-out flights 13-24 13.798 -> 13.578
    (-0.22 +- 0.34, 8 of 12), ARE 0.1608 -> 0.1571; 346x260 flights 1-12 and 15 11.198 -> 9.239 (-1.96 +- 0.99, 12 of
    13), ARE 0.1569 -> 0.1320; nominal 240x180 seeds 0-23 4.922 -> 4.787 (-0.13 +- 0.09, 14 of 24), ARE 0.0562 ->
    0.0547; nominal 346x260 seeds 0-23 4.204 -> 4.051 (-0.15 +- 0.06, 16 of 24), ARE 0.0471 -> 0.0462; nominal
    240x180 seeds 24-35 5.292 -> 5.219 (-0.07 +- 0.14, 7 of 12), ARE 0.0592 -> 0.0609. ON -0.2, OFF 0:
    11.054 (-1.07 +- 0.39, 11 of 12); 13.895 (+0.10 +- 0.35, 6 of 12); 10.163 (-1.04 +- 0.48, 11 of 13); 4.776 (-0.15 +-
    0.15, 15 of 24); 4.027 (-0.18 +- 0.11, 14 of 24). ON -0.15, OFF 0: 11.774 (-0.35 +- 0.22, 10 of 12); nominal
    240x180 4.802 (-0.12 +- 0.15, 15 of 24). But the bundled demos (346x260, 4 s; main 7.530 / 8.718 / 7.748
    mm, session 41's 0 / 0 6.554 / 9.035 / 6.012) do not come back: ``landing`` / ``landing_fast`` /
    ``landing_dynamic`` 8.261 / 9.342 / 6.796 (-0.2 / -0.05), 8.249 / 9.659 / 6.067 (-0.2 / 0), 7.719 / 9.508 / 6.073
    (-0.15 / 0). On ``landing`` (``evdump.py``, counts pooled per second) the lone ON events trail the other ON events
    by only 0.07 px over its 4 s (0.15 in its first second; in its third, where 54 % of its ON events count as lone,
    they lead them by 0.04), the lone OFF events +0.01 px from the other OFF ones.
    -0.2 / -0.05 since session 43 (the lead): better on the tuning flights and on all five other sets, the nominal
    spiral included (60 recordings); the demos are single runs of that spiral, and of the three one gains and two
    lose 0.6-0.7 mm. -0.1 / -0.1 gives session 42's outputs (to rounding: session 43's compiled registration)."""
    lone_off_lead_px: float = field(default=-0.05, metadata={"min": -1.0, "max": 1.0, "step": 0.01, "unit": "px"})
    """Added to the OFF lead of a point whose events come one per pixel passage, pixels (0 = off). Session 43's oracle
    dumps put the lone OFF events +0.03 / -0.17 / +0.04 px (240x180 flights 2 / 9 / 1) and +0.11 / +0.09 / +0.09
    (nominal seeds 0 / 1 / 2) from the other OFF events; with ``lone_on_lead_px`` -0.2, -0.05 and 0 were measured (the
    figures there)."""
    lone_max_ratio: float = field(default=1.15, metadata={"min": 1.0, "max": 5.0, "step": 0.05, "unit": "events/passage"})
    """A point whose running events per passage (events over the passage-starting ones) is below this fires 'one per
    passage', events per passage."""
    crossings: float = field(default=2.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "crossings"})
    """An event starts a passage when its pixel fired no same-polarity event within this many of its edge's
    pixel-crossing times (``1 / |v|``, ``v`` the point's normal image speed from the twist), crossings."""
    memory_events: float = field(default=50.0, metadata={"min": 1.0, "max": 1e6, "step": 1.0, "unit": "events"})
    """Memory of the running counts: each associated event scales the point's counts by ``1 - 1 / this``, events."""
    min_events: float = field(default=10.0, metadata={"min": 0.0, "max": 1e6, "step": 1.0, "unit": "events"})
    """Counted events (running, with the memory) a point needs before its ratio is trusted, events."""
    pool_radius_m: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.005, "unit": "m"})
    """A point's ratio and its ``min_events`` read the summed counts of the map points within this distance whose
    edges run parallel to its own (absolute tangent cosine at least ``pool_min_cos``), metres (0 = its own counts
    only). The built maps hold a point every few millimetres, so along a low-contrast edge each point sees only 2-5
    events in its first second (session 42: a building's foot on flights 2 / 9, ratio 1.0, median 3.9 counted
    events at 0.8 s) and is never trusted alone. 0.05 since session 42 (figures at ``lone_on_lead_px``); building the
    neighbour lists takes ~1 s at start-up on a 97,000-point map (``pool_neighbours``, under load)."""
    pool_min_cos: float = field(default=0.9, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "cos"})
    """Least absolute cosine between two points' edge tangents for ``pool_radius_m`` to pool their counts, cosine."""


def coverage_lead(L0: float, L1: float, motion: np.ndarray, lo: float, hi: float, samples: np.ndarray) -> float:
    """Mean lead (pixels, + = ahead of the edge along the unit image direction ``motion``) of a pixel's events as an
    edge moving along ``motion`` turns the pixel from log level ``L0`` to ``L1``, the events uniform in the log
    change ``|L - L0|`` over ``[lo, hi]`` (clipped to ``|L1 - L0|``; NaN when empty), the pixel's intensity the mean
    of its sub-pixel ``samples`` ((N, 2) offsets from the pixel centre in pixels; the simulator's are
    :func:`evpose.sim.render.subpixel_pattern`, passed in since the tracker does not depend on the simulator)."""
    y = np.sort(np.asarray(samples, np.float64) @ np.asarray(motion, np.float64))  # the order the edge covers them
    n = y.size
    f = np.arange(n + 1) / n
    lev = np.abs(np.log(f * np.exp(L1) + (1 - f) * np.exp(L0)) - L0)
    hi = min(float(hi), abs(L1 - L0))
    if not hi > lo:
        return float("nan")
    w = np.clip(lev[1:], lo, hi) - np.clip(lev[:-1], lo, hi)
    return float(-np.sum(y * w) / (hi - lo))


@nb.njit(cache=True)
def _count_passages(n, assoc, used, pts, tg, eg, R_cw, t_cw, fx, fy, cx, cy, twist, crossings, decay, events, starts):  # pragma: no cover
    # Per point of `used` its normal image speed (the camera's twist moving the point), then per associated event
    # whether it starts a passage (its pixel's previous same-polarity event older than `crossings` / |v|).
    m = used.shape[0]
    speed = np.zeros(m)
    for k in range(m):
        X0 = R_cw[0, 0] * pts[k, 0] + R_cw[0, 1] * pts[k, 1] + R_cw[0, 2] * pts[k, 2] + t_cw[0]
        X1 = R_cw[1, 0] * pts[k, 0] + R_cw[1, 1] * pts[k, 1] + R_cw[1, 2] * pts[k, 2] + t_cw[1]
        X2 = R_cw[2, 0] * pts[k, 0] + R_cw[2, 1] * pts[k, 1] + R_cw[2, 2] * pts[k, 2] + t_cw[2]
        if X2 <= 1e-6:
            continue
        T0 = R_cw[0, 0] * tg[k, 0] + R_cw[0, 1] * tg[k, 1] + R_cw[0, 2] * tg[k, 2]
        T1 = R_cw[1, 0] * tg[k, 0] + R_cw[1, 1] * tg[k, 1] + R_cw[1, 2] * tg[k, 2]
        T2 = R_cw[2, 0] * tg[k, 0] + R_cw[2, 1] * tg[k, 1] + R_cw[2, 2] * tg[k, 2]
        a = fx * (T0 * X2 - X0 * T2)
        c = fy * (T1 * X2 - X1 * T2)
        L = np.sqrt(a * a + c * c)
        if L <= 0.0:
            continue
        # camera body twist (w, v): a static point moves by -(w x X) - v in the camera frame
        D0 = -(twist[1] * X2 - twist[2] * X1) - twist[3]
        D1 = -(twist[2] * X0 - twist[0] * X2) - twist[4]
        D2 = -(twist[0] * X1 - twist[1] * X0) - twist[5]
        ud = fx * (D0 * X2 - X0 * D2) / (X2 * X2)
        vd = fy * (D1 * X2 - X1 * D2) / (X2 * X2)
        speed[k] = abs(-c / L * ud + a / L * vd)
    for i in range(n):
        k = assoc[i]
        g = used[k]
        start = 1.0 if eg[i] * speed[k] * 1e-6 >= crossings else 0.0
        events[g] = decay * events[g] + 1.0
        starts[g] = decay * starts[g] + start


@nb.njit(cache=True)
def _add_lone(used, events, starts, min_events, max_ratio, lead_on, lead_off, on, off, indptr, indices):  # pragma: no cover
    # With neighbour lists (``indptr`` of N + 1 entries, CSR, each point's own row included) a point reads the sums of
    # its neighbours' counts; an empty ``indptr`` = its own counts.
    pooled = indptr.shape[0] > 0
    for k in range(used.shape[0]):
        g = used[k]
        e, s = events[g], starts[g]
        if pooled:
            e, s = 0.0, 0.0
            for q in range(indptr[g], indptr[g + 1]):
                e += events[indices[q]]
                s += starts[indices[q]]
        if e >= min_events and s > 0.0 and e < max_ratio * s:
            on[k] += lead_on
            off[k] += lead_off


def pool_neighbours(points: np.ndarray, tangents: np.ndarray, radius: float, min_cos: float) -> tuple[np.ndarray, np.ndarray]:
    """CSR neighbour lists (``indptr`` (N + 1,), ``indices``) of the map points (``points`` (N, 3) metres, ``tangents``
    (N, 3) unit edge directions, zero = none) within ``radius`` of each other whose tangents' absolute cosine is at
    least ``min_cos``; each point with a tangent lists itself, in ascending order. Empty arrays when ``radius`` <= 0."""
    if not float(radius) > 0:
        return _NO_INDEX, _NO_INDEX
    p = np.asarray(points, np.float64)
    t = np.asarray(tangents, np.float64)
    n = len(p)
    has = np.einsum("ij,ij->i", t, t) > 0.25
    pairs = cKDTree(p).query_pairs(float(radius), output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        keep = has[i] & has[j] & (np.abs(np.einsum("ij,ij->i", t[i], t[j])) >= float(min_cos))
        i, j = i[keep], j[keep]
    else:
        i = j = np.zeros(0, np.int64)
    own = np.flatnonzero(has)
    rows = np.concatenate([i, j, own])
    cols = np.concatenate([j, i, own])
    order = np.lexsort((cols, rows))
    rows, cols = rows[order], cols[order]
    indptr = np.zeros(n + 1, np.int64)
    np.add.at(indptr, rows + 1, 1)
    return np.cumsum(indptr), cols.astype(np.int64)


_NO_INDEX = np.zeros(0, np.int64)


class PassageCounts:
    """Running events and passage-starting events per map point (the state of :class:`ContrastLeadConfig`)."""

    def __init__(self, config: ContrastLeadConfig, n_points: int, points: np.ndarray | None = None,
                 tangents: np.ndarray | None = None):
        self.config = config
        self._indptr, self._indices = _NO_INDEX, _NO_INDEX
        if points is not None and tangents is not None:
            self._indptr, self._indices = pool_neighbours(points, tangents, float(config.pool_radius_m), float(config.pool_min_cos))
        self.events = np.zeros(int(n_points))
        """Running count of each point's associated events (memory ``memory_events``)."""
        self.starts = np.zeros(int(n_points))
        """Running count of those that started a pixel passage."""

    def update(self, n: int, assoc, used, pts, tg, eg, R_cw, t_cw, K, twist) -> None:
        """Counts the first ``n`` associated events (``assoc`` their rows of ``used``, ``pts`` / ``tg`` the gathered
        points / tangents, ``eg`` their pixels' same-polarity gaps, us) at the camera ``R_cw``, ``t_cw`` moving with the
        body ``twist`` (per second, gtsam order; none = nothing counted)."""
        c = self.config
        if twist is None or len(twist) != 6 or n <= 0:
            return
        _count_passages(int(n), assoc, np.ascontiguousarray(used, np.int64), pts, tg, eg, R_cw, t_cw, float(K[0, 0]),
                        float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), np.ascontiguousarray(twist, np.float64),
                        float(c.crossings), 1.0 - 1.0 / max(float(c.memory_events), 1.0), self.events, self.starts)

    def add_leads(self, used, on: np.ndarray, off: np.ndarray) -> None:
        """Adds ``lone_on_lead_px`` / ``lone_off_lead_px`` to the ON / OFF leads (as ``used``) of the points firing one
        event per passage."""
        c = self.config
        _add_lone(np.ascontiguousarray(used, np.int64), self.events, self.starts, float(c.min_events), float(c.lone_max_ratio),
                  float(c.lone_on_lead_px), float(c.lone_off_lead_px), on, off, self._indptr, self._indices)

    def ratio(self) -> np.ndarray:
        """Each point's running events per passage (NaN before any passage)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.starts > 0, self.events / np.where(self.starts > 0, self.starts, 1.0), np.nan)

    def snapshot(self):
        return np.copy(self.events), np.copy(self.starts)

    def restore(self, state) -> None:
        """Back to ``state`` (of :meth:`snapshot`), or to no counts when None."""
        if state is None:
            self.events.fill(0.0)
            self.starts.fill(0.0)
        else:
            self.events, self.starts = np.copy(state[0]), np.copy(state[1])
