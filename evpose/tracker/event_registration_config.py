"""Settings of the events registered at their own timestamps in the fused modes (:class:`EventRegistrationConfig`).

Kept in its own module, beside :mod:`evpose.tracker.event_registration` (the method): most of its fields carry the
measurements that set them. "See the module" in them means that module's docstring, which has the figures.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from evpose.tracker.contrast_leads import ContrastLeadConfig
from evpose.tracker.edge_clusters import EdgeClusterConfig
from evpose.tracker.event_lag import EventLagConfig


@dataclass
class EventRegistrationConfig:
    """Events registered at their own timestamps, combined with the fused modes' field registration (see the module)."""

    enabled: bool = True
    """Register the step's events in ``full`` (the fusion's twist moves each map point to its event's time).

    Off: the field registration alone (7.77 / 7.95 and 8.11 / 10.46 mm, see the module)."""
    combine: bool = True
    """Combine the events' pose with the field registration's by their covariances (information-weighted, in the
    field pose's tangent space); False = replace it. Replacing (seeds 0-3 / 4-7): 6.08 / 5.78 mm at 346x260 but
    8.90 mm (seeds 0-3) at 240x180, where the events hold the depth along the optical axis poorly (seed 1: 9.1 mm
    RMS against the field's 3.3); combined 6.28 / 5.84 and 7.38 / 8.54 mm (3 px association radius). The field's
    covariance scaled 3 / 10x before combining: 6.02 / 5.53, 5.81 / 5.59 mm at 346x260 but 7.45 / 9.48, 7.78 / 10.41 mm
    at 240x180. Replacing, the 4 s demos: 10.85 / 7.98 / 7.61 mm (``landing`` / ``fast`` / ``dynamic``). Replacing with
    a 2 px association radius, 346x260 seeds 0-3 / 4-7: 6.11 / 5.81 mm (ARE 0.070 / 0.072 deg against 0.066 / 0.068),
    but the EKF backend then beats the graph (6.06 / 5.72 mm). Session 15 (the field echoes the prediction, see the
    module), the field's covariance scaled 10x before combining, 3 s landings at 346x260 (``/tmp/s13/dyn/plain3.h5``
    on the bundled map, ``/tmp/s14/fullacc/sim3`` seeds 1-3 on their built maps): 12.47 / 18.38 / 16.33 / 15.28 ->
    8.52 / 13.59 / 12.66 / 12.26 mm, but the ``landing`` demo 9.71 -> 10.99 mm (3x / 5x: 10.49 / 10.80 mm): not kept.
    Its variance along the optical axis alone 10x: 2 s seeds 0-3 6.09 mm at 346x260, 7.89 at 240x180, the 3 s
    ``plain3`` 13.09 mm, the demo 10.22 mm; its tilt and sideways variances 10x: 7.55 mm at 346x260."""
    combine_convex: bool = True
    """With ``combine``: the combined pose weighs each tangent component (field pose's frame) by the two diagonal
    informations alone, so it lies between the field's and the events' poses component by component (the covariance
    stays the full combination); False = the full information-weighted mean, which can land beyond both along a
    direction both hold poorly (session 32, below; the default since then: better on the held-out seeds, 346x260, the
    3 s landing and two of the three demos, ``evpose track demo_data/landing.h5 --map maps/landing_map.ply`` now hashes
    ``df748492ded2f3b2``).

    Session 32 (``/tmp/s32/edge32/``: ``stages.py`` logs every update's prediction, field pose, events' pose and
    combined pose against the truth; ``run.sh``, ``cmp.py``, ``bias.py``, ``demo.sh``). Where the along-motion bias of
    240x180 lives (defaults, 2 s landing seeds 0-5, mean camera-frame error x (the flight's direction) / rotation about
    y): prediction +3.13 mm / -48 mdeg, field registration +0.41 / -21, events' pose +1.89 / -29, combined +2.77 / -44.
    The combination lands beyond both inputs along the tilt-about-y / shift-along-x ridge (the two hold it in
    different combinations), the fusion keeps it, and the next prediction starts from it; the field alone is nearly
    unbiased along x. With this on (seeds 0-5): prediction +2.54 / -37.5, field +0.28 / -16.2, events +1.63 / -23.3,
    combined +1.45 / -19.5: the combination now stays between, but the prediction (fused state + IMU) still runs
    ahead of every registration it is fed, which is where the rest of the bias is made. The same with the burst leads (``follower_crossings``) or the events' prior 0.24 px
    (``prior_residual_px``): field +0.05 / +0.59, events +1.49 / +1.46, combined +2.63 / +2.98 mm.

    On (``full`` from ground truth, mean ATE mm, paired change +- standard error, seeds better, ARE deg):
    240x180 2 s seeds 0-23 5.984 -> 5.568 (-0.42 +- 0.11, 20 of 24), ARE 0.0736 -> 0.0667, along-motion bias +2.80 ->
    +2.13 mm; held-out seeds 24-47 6.821 -> 6.091 (-0.73 +- 0.13, 22 of 24), ARE 0.0828 -> 0.0707,
    along-motion bias +3.30 -> +2.40 mm (seeds 0-47 6.403 -> 5.829, -0.57 +- 0.08, 42 of 48); 3 s landing at 240x180 seeds 0-7 16.982 -> 15.889 (-1.09 +- 0.28, 7 of 8),
    ARE 0.1130 -> 0.1055; 346x260 2 s seeds 0-11 4.308 -> 4.313 (+0.005 +- 0.069, 6 of 12), ARE 0.0537 -> 0.0522,
    seeds 12-23 4.910 -> 4.745 (-0.17 +- 0.10, 9 of 12), seeds 0-23 4.609 -> 4.529 (-0.08 +- 0.06, 15 of 24), ARE
    0.0562 -> 0.0538;
    bundled demos (``evpose track demo_data/X.h5 --map maps/landing_map.ply``, ``evpose eval --align none``)
    ``landing`` 6.569 -> 6.615 mm (ARE 0.0525 -> 0.0537), ``landing_fast`` 10.108 -> 9.357 (0.0990 -> 0.0832),
    ``landing_dynamic`` 5.907 -> 5.697 (0.0544 -> 0.0561). Per seed, 240x180 seeds 0-23: 7.42 5.65 7.88 5.07 6.37
    3.40 5.75 4.11 6.14 3.86 4.71 8.67 5.44 4.77 6.86 3.75 5.37 5.25 8.51 5.33 8.63 5.71 7.48 7.50 -> 6.93 5.81 7.81
    4.31 5.83 3.07 5.18 4.49 5.66 4.22 3.93 7.43 5.15 4.10 6.69 4.24 5.29 5.01 7.00 5.25 7.38 5.40 6.93 6.52; 3 s
    12.95 15.06 14.74 18.90 17.33 19.73 19.09 18.07 -> 11.84 14.56 12.85 18.99 16.51 17.27 18.14 16.96; seeds 24-47
    8.04 7.75 6.06 7.15 9.04 9.10 4.64 5.21 6.65 8.08 6.87 6.76 6.26 4.62 7.10 5.53 5.26 6.84 5.52 8.25 7.46 7.22 7.16
    7.15 -> 7.42 6.56 6.32 7.51 7.42 8.59 4.50 4.09 6.65 7.18 5.44 5.53 5.27 4.56 5.78 4.83 4.88 4.97 5.46 7.91 6.98
    6.05 6.48 5.80; 346x260 seeds 0-11 4.59 5.21 5.79 4.07 2.51 2.29 4.42 5.12 4.67 3.19 4.18 5.65 -> 4.50 5.35 5.64
    4.03 2.78 2.45 4.70 4.82 4.46 3.43 4.37 5.23."""
    covariance_scale: float = field(default=70.0, metadata={"min": 0.001, "max": 100000.0, "step": 1.0, "unit": "ratio"})
    """Factor on the events' covariance ``(J^T W J)^-1 sigma^2`` (``sigma^2`` their weighted residual variance), ratio.

    70 with ``gate_px`` 0.72 and ``huber_px`` 0.24 since session 29 (300 / 1.5 / 0.5 before; the figures under
    ``gate_px``); the older figures below are with the older thresholds. Around the new defaults (lead,
    ``/tmp/s29/lead/sweep.sh``; ``full``, 2 s landing from ground truth, seeds 0-11, mean ATE mm, defaults 4.621 at
    346x260 / 5.438 at 240x180): 35 gave 4.804 / 5.229, 140 4.611 / 5.802; ``gate_px`` 0.5 with ``huber_px`` 0.17
    5.149 / 5.777. Nothing clearly better at both resolutions; kept.

    A step's ~1000 events claim ~0.01 px but share the map's slowly learned errors from update to update. Seeds
    0-3, 346x260, replacing (3 px association radius): 1 / 3 / 10 / 30 / 100 / 300 / 1000 / 3000 gave 16.1 (seed 0)
    / 8.07 / 7.37 / 6.94 / 6.36 / 6.08 / 6.02 / 7.04 mm (seeds 4-7 at 300 / 1000: 5.78 / 7.16); 240x180 30 / 100 /
    300 / 1000: 9.56 / 8.76 / 8.90 / 10.36 mm; combined at 240x180 100 / 300 / 1000: 7.71 / 7.38 / 7.74 mm, at
    346x260 30 / 100 / 300: 6.62 / 6.32 / 6.28 mm."""
    association_radius_px: float = field(default=2.0, metadata={"min": 0.5, "max": 10.0, "step": 0.5, "unit": "px"})
    """An event is associated with the nearest used map point projected within this distance, pixels.

    3 px (the other figures in this class): seeds 0-3 / 4-7 6.28 / 5.84 mm at 346x260, 7.38 / 8.54 mm at 240x180,
    the demos 9.42 / 14.28 / 11.61 mm, but ~0.15 ms more CPU per update and the EKF backend level with the graph
    (346x260 seeds 0-3 6.28 / 0.0677 deg against the graph's 6.28 / 0.0684); 2 px 6.38 / 5.91, 7.25 / 8.49 mm
    (EKF 6.58 / 6.00, 7.31 / 8.54 mm). Replacing, 346x260 seeds 0-3: 2 / 3 px 6.11 / 6.08 mm."""
    gate_px: float = field(default=0.72, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Events farther than this from their point's edge line (at the current pose) take no part, pixels (2 px: 6.34
    mm against 6.08; seed 0 without the painted mask 0.7 / 1.0 px: 17.7 / 16.1 mm against 16.1).

    Session 29: 0.72, with ``huber_px`` 0.24 and ``covariance_scale`` 70 (1.5 / 0.5 / 300 before), found at 240x180
    (``angle_reference_pixel_mrad``, ``covariance_pixel_exponent``) and then made the defaults at every resolution by
    the lead (``/tmp/s29/reg29/run.py``, ``/tmp/s29/lead/reg.sh``; ``full``, 2 s landing from ground truth, mean ATE
    mm): 346x260 seeds 0-11 5.091 -> 4.621 (paired -0.47 +- 0.25, 7 of 12 better; seeds 0-3 / 4-7 / 8-11 5.84 / 4.77
    / 4.67 -> 5.34 / 4.39 / 4.14; ARE 0.0552 -> 0.0575 deg), 240x180 seeds 0-11 6.906 -> 5.438 (-1.47 +- 0.41, 10 of
    12 better; ARE 0.077 -> 0.063 deg), 3 s landing 346x260 seeds 0-3 12.147 -> 7.399 (all four better; ARE 0.133 ->
    0.078); the demos ``landing`` / ``landing_fast`` / ``landing_dynamic`` 9.95 / 18.56 / 10.44 -> 7.12 / 9.98 / 5.90
    mm (ARE 0.108 / 0.171 / 0.112 -> 0.062 / 0.090 / 0.063 deg), degraded updates 45 / 0 / 61 -> 43 / 0 / 45, none
    lost; ``evpose track demo_data/landing.h5 --map maps/landing_map.ply`` now hashes ``1c3f8d90bee2efe8``."""
    huber_px: float = field(default=0.24, metadata={"min": 0.01, "max": 10.0, "step": 0.05, "unit": "px"})
    """Huber scale on the events' distances, pixels (0.3: 6.04 mm against 6.08, replacing, 3 px association radius).

    With ``gate_px`` 1.0 (combined, 2 px): seeds 0-3 / 4-7 6.29 / 5.59 mm at 346x260 and 7.25 / 8.30 mm at 240x180
    (ARE 0.062 / 0.066, 0.072 / 0.086 deg), the demos 9.47 / 16.84 / 12.35 mm, but the EKF backend then beats the
    graph at 240x180 (7.22 / 8.18 mm, ARE 0.073 / 0.085 deg): not kept."""
    angle_reference_pixel_mrad: float = field(default=0.0, metadata={"min": 0.0, "max": 100.0, "step": 0.01, "unit": "mrad"})
    """On a sensor whose pixel subtends more than this angle (``1 / fx``), ``gate_px`` and ``huber_px`` shrink by
    ``(this / pixel) ** angle_pixel_exponent`` and ``covariance_scale`` by ``(this / pixel) **
    covariance_pixel_exponent``, milliradians (0, the default since the lead made the 240x180 values below the
    defaults at every resolution: they stay as set; the measurements below are of the rule at 4.05 mrad with
    session 28's thresholds 1.5 / 0.5 px and 300). They were tuned on the simulated 346x260
    70 deg camera (4.05 mrad: unchanged there, as on the bundled demos); its 240x180 sibling (5.83 mrad) gets 0.72 /
    0.24 px and 70 instead of 1.5 / 0.5 px and 300 (the figures with all three: ``covariance_pixel_exponent``).

    What they bound is how far an event may sit from its edge line for the map's and the edge's own errors (a few
    millimetres on the map, 0.1-0.3 px of polarity lead at 346x260), an angle rather than a pixel count: a coarser
    pixel spans more of it, and the same 1.5 px let in events 1.44x further off. Measured, shrinking them further
    than the angle (exponent 2) helps 240x180 more still, while at 346x260 the angle-kept 240x180 values (1.04 / 0.35
    px) change little (seeds 0-7 5.302 -> 5.266 mm): at 240x180 the events' distances from the built map's edges
    are wider in pixels than the 346x260 tuning assumed.

    Session 29 (``/tmp/s29/reg29/run.py``, ``queue*.sh``; ``full``, 2 s landing from ground truth, mean ATE mm / ARE
    deg at 240x180; 346x260 and the bundled demos bit-identical, ``evpose track demo_data/landing.h5`` still
    ``469f53f67bcd8fbb``), ``covariance_scale`` as set (300), off / exponent 1 / 1.5 / 2 (the default) / 3: seeds 0-7 6.955 / 6.727 / 6.575 / 6.521 /
    6.502 (ARE 0.0772 / 0.0759 / 0.0727 / 0.0728 / 0.0723), held-out seeds 8-11 6.807 / 6.452 / 6.290 / 6.225 / -, 3 s
    landing seeds 0-3 18.897 / 18.132 / 17.172 / 16.217 / - (ARE 0.186 / 0.174 / 0.161 / 0.153 / -). Per seed, off ->
    exponent 2: seeds 0-7 9.93 4.87 8.89 4.17 10.13 5.32 6.10 6.23 -> 9.94 5.26 8.75 3.71 9.53 4.57 5.54 4.87, seeds
    8-11 6.30 6.78 3.51 10.64 -> 5.83 5.30 3.49 10.27, 3 s 21.60 16.59 15.76 21.64 -> 16.60 15.83 13.58 18.85. The factors rounded (0.6947 ** exponent):
    exponent 1 6.813 / 6.508 mm, 2 6.493 / 6.121 mm (seeds 0-7 / 8-11; 3 s 16.659), so the runs' chaotic spread of
    an 8-seed mean is 0.03-0.1 mm. Exponent 2 against off, paired over the twelve 2 s seeds: -0.48 +- 0.16 mm, 10 better (ARE 0.0772 / 0.0796 -> 0.0728 / 0.0651 deg on seeds 0-7 / 8-11); the 3 s landings all four better. Alone (pixels, seeds 0-7): ``gate_px`` 1.0 6.754, ``huber_px`` 0.35 6.860 mm.
    Where it acts (every update of seeds 0-7, camera frame at the truth, RMS, off / exponent 1 / 2): the fused
    sideways / height error 4.97 / 4.40, 4.81 / 4.28, 4.54 / 4.24 mm, its rotation about x (the tilt paired with the
    sideways shift) 57.6 / 58.0 / 54.1 mdeg, the slow part (50-update mean) of the registration's height error 3.74 /
    3.59 / 3.55 mm. 3 s landing seeds 4-7 (not used to choose): 26.405 -> 23.165 mm (25.50 21.30 29.49 29.33 -> 23.44
    17.63 26.82 24.77), ARE 0.196 -> 0.162 deg. Not scaled: ``association_radius_px`` 1.5 (seeds 0-7, without this) 7.041 mm;
    ``offset_clip_px`` 0.69 (exponent 1) the same figures to the last digit (the gate already bounds the distances)."""
    angle_pixel_exponent: float = field(default=2.0, metadata={"min": 0.0, "max": 4.0, "step": 0.1, "unit": "ratio"})
    """Power of ``angle_reference_pixel_mrad / pixel`` that ``gate_px`` and ``huber_px`` shrink by on coarser sensors: 1
    keeps their angle, 2 (the default) shrinks them further, as measured at 240x180 (see ``angle_reference_pixel_mrad``),
    ratio."""
    covariance_pixel_exponent: float = field(default=4.0, metadata={"min": 0.0, "max": 4.0, "step": 0.1, "unit": "ratio"})
    """Power of ``angle_reference_pixel_mrad / pixel`` that ``covariance_scale`` shrinks by on coarser sensors (0 = it
    stays), ratio: 300 -> 70 at 240x180 with 4.

    With the thresholds shrunk (exponent 2), the events' weight against the field's is no longer at its optimum at
    240x180 (session 29, ``/tmp/s29/reg29/queue12-15.sh``; ``full``, 2 s landing from ground truth, mean ATE mm, the
    scale set by hand): seeds 0-7 600 / 300 / 150 / 75 / 37.5 gave 7.012 / 6.521 / 6.027 / 5.564 / 5.382; held-out
    seeds 8-11 300 / 150 / 75 6.225 / 5.567 / 5.103; 3 s landing seeds 0-3 300 / 150 / 75 16.217 / 15.350 / 14.016.
    With this default (70 at 240x180), against session 28's defaults (thresholds and scale as at 346x260): seeds 0-7
    6.955 -> 5.532 mm (per seed 9.93 4.87 8.89 4.17 10.13 5.32 6.10 6.23 -> 7.84 5.44 7.99 3.63 5.81 3.91 5.33 4.30;
    seeds 0-3 / 4-7 6.23 / 4.84), ARE 0.0772 -> 0.0674 deg; held-out seeds 8-11 6.807 -> 5.257 (6.30 6.78 3.51 10.64
    -> 4.73 5.09 3.79 7.42), ARE 0.0796 -> 0.0577; paired over the twelve -1.47 +- 0.40 mm, 10 better; 3 s landing
    seeds 0-3 18.897 -> 14.133 (21.60 16.59 15.76 21.64 -> 10.07 17.28 13.02 16.16), seeds 4-7 26.405 -> 17.717
    (25.50 21.30 29.49 29.33 -> 16.24 15.47 19.55 19.61), ARE 0.186 / 0.196 -> 0.119 / 0.097 deg. 346x260 seeds 0-1 and
    the ``landing`` demo bit-identical. Where it acts (every update of seeds 0-7, camera frame at the truth, RMS,
    session 28's defaults -> these): the fused translation error x / y / z 2.86 / 4.97 / 4.40 -> 2.98 / 3.36 / 3.25 mm,
    rotation about x / y / z 57.6 / 30.5 / 47.4 -> 46.3 / 38.7 / 33.0 mdeg; the registrations' slow (50-update mean)
    y / height error 4.70 / 3.74 -> 4.05 / 3.06 mm, their x and y-rotation noisier (slow 4.09 -> 4.89 mm, 53 -> 66
    mdeg): the sideways / height pair is no longer the largest part. The scale is a 240x180 optimum found on seeds 0-7 (37.5 still lower there):
    346x260 may gain too (its sweep, session 12, had 300 best with 1.5 / 0.5 px): 0.72 / 0.24 px and 70 there by
    hand, seeds 0-7 5.302 -> 4.862 mm (6.65 5.31 7.72 3.68 4.94 3.95 5.23 4.95 -> 5.82 5.44 5.74 4.34 3.40 4.04 4.61
    5.50, ARE 0.0592 -> 0.0610 deg); the bundled demos (``evpose track ... --config`` with those three, ``evpose eval
    --align none``, ATE RMSE / ARE) ``landing`` 9.953 -> 7.124 mm / 0.108 -> 0.062 deg, ``landing_fast`` 18.560 ->
    9.981 / 0.171 -> 0.090, ``landing_dynamic`` 10.435 -> 5.897 / 0.112 -> 0.063; held-out seeds 8-11 4.670 -> 4.137
    (4.36 4.68 3.42 6.22 -> 3.80 4.92 3.15 4.68, ARE 0.0472 -> 0.0505); 3 s landing seeds 0-3 12.147 -> 7.399 (9.85
    14.66 12.72 11.36 -> 5.85 9.56 6.37 7.81, ARE 0.133 -> 0.078). Found at the end of session 29 and not applied
    (it moves the pinned demo output and every 346x260 figure): the first thing to try next, as new defaults for
    every sensor with this scaling re-based."""
    on_lead_px: float = field(default=0.0, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """How far ahead of its edge along the edge's image motion an ON event fires (negative: behind), pixels.

    Simulated landing (seed 0, the simulator's true edges, at the truth, events of 5 ms), 346x260 / 240x180: ON -0.01
    / -0.02 px, OFF -0.17 / -0.17 px (a pixel's log response: crossing from bright to dark its events come late), no
    trend with the event's age beyond 0.05 px over 0-5 ms: no lag. Against the built map the same events read ON
    +0.21, OFF -0.16 px and spread by 0.60 px instead of 0.34 px (the map's own errors). 346x260 seeds 0-3,
    replacing: ON +0.1 6.43 mm, OFF 0 / -0.25 7.33 / 6.18 mm against 6.08."""
    off_lead_px: float = field(default=-0.11, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """As ``on_lead_px`` for OFF events, pixels. -0.17 until session 17, where ``crease_radius_m`` split the face-on
    points: this is now the lead of those neither on a crease nor seen past (their events -0.08 to -0.11 px)."""
    grazing_max_cos: float = field(default=0.6, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Points whose surface is seen at a grazing angle, the absolute cosine between the map's plane normal and the
    ray from the camera below this, take ``grazing_on_lead_px`` / ``grazing_off_lead_px`` instead of ``on_lead_px`` /
    ``off_lead_px``, and their OFF fields trail ``registration.fused_grazing_off_trail_px`` further (0 = off; points
    without a plane normal never do), ratio.

    Measured (session 17, scripts in ``/tmp/s17/polbias7/``, ``measure.py``): every 5th event registration of
    closed-loop ``full`` runs, the step's events associated at the true pose, each event's distance along its point's
    image normal from the point projected at the true pose *at the event's time*, signed along the point's image
    motion, non-painted points within 30 mm of a true edge. Against the simulator's true edges (346x260 and 240x180,
    seeds 0 / 1 / 4 each, 15-38 k events per run): ON events -0.01 to +0.05 px, OFF -0.18 px as ``off_lead_px``
    says, but OFF events of grazing points (|cos| < 0.6: the boxes' vertical faces seen from above, a third of the OFF
    events) sit -0.26 to -0.29 px behind their edge (pooled -0.28; -0.23 to -0.27 against the events' own map), those
    of face-on points -0.125 to -0.148 (pooled -0.135); ON -0.03 to +0.07 / -0.06 to -0.08. Nothing else the tracker sees moves them as much: the event's age (0-5 ms) within 0.05
    px, the normal image speed -0.19 ms x speed (OFF) / -0.09 ms (ON), the event's pixel multiplicity (a stand-in for
    the edge's contrast) within 0.09 px, whether the edge moves out of or into its region (the map's outward normal
    along or against the motion) up to 0.15 px but not alike on every surface. Per point the offset from the true
    edge is stable (split-half correlation 0.85; 0.13-0.19 px between points), and 99.5 % of the points fire one
    polarity only. The pose those offsets imply at the truth (``screen.py``: the events' normal equations with the
    run's prior, averaged over 0.25 s), slow part per run 6.42 / 6.07 / 5.06 mm (346x260 seeds 0 / 1 / 4) and 6.13 /
    5.56 / 5.39 (240x180): with the grazing OFF lead 5.95 / 5.62 / 4.69 and 5.41 / 4.87 / 4.70; with each event's own
    true offset as its lead (an oracle) 3.45 / 4.47 / - and 1.15 / - / -; with the map on the true edges instead
    (leads kept) 5.44 / 6.29 / - and 6.05.

    ``full``, 2 s landing, mean ATE of 346x260 seeds 0-3 / 4-7 and 240x180 seeds 0-3 / 4-7 (``/tmp/s13/acc/run.py``;
    the four sets' average): off 6.38 / 5.91 / 7.25 / 8.49 (7.01); this alone (grazing OFF lead -0.28) 6.12 / 5.50 /
    7.46 / 7.97 (6.76); with ``fused_grazing_off_trail_px`` 0.1 / 0.2 (the defaults) / 0.3: 6.14 / 5.48 / 7.42 / 7.63
    (6.67), **6.12 / 5.28 / 7.35 / 7.52 (6.57)**, ARE 0.064 / 0.065 / 0.079 / 0.085 deg, 5.99 / 5.12 / 7.58 / 7.28
    (6.49); with 0.2 at ``grazing_max_cos`` 0.7 6.07 / 5.27 / 7.37 / 7.55 (6.56); that field trail alone (events' leads as off) 6.32 / 5.65 / 7.27 / 8.12 (6.84); grazing leads -0.35 / ON
    +0.06 (no field trail) 6.21 / 5.68 / 7.74 / 7.82 (6.86); the whole measured table (face-on ON -0.07, OFF -0.135,
    grazing ON +0.05, OFF -0.28, field trail 0.1) 6.03 / 5.50 / 7.31 / 7.90 (6.69); the face-on OFF lead split by
    the edge's motion along / against its outward normal (measured -0.04 / -0.20 px, -0.011 to -0.077 / -0.193 to
    -0.205 in every run; ``run_nside.py``) 5.99 / 5.14 / 7.41 / 7.67 (6.55), the grazing one too (-0.32 / -0.25) 5.94
    / 5.20 / 7.55 / 7.66 (6.59): 346x260 against 240x180 again, not kept. 3 s landings (``landing_case``
    3 s, ``fusion.ablation_long``'s flights), off -> on: 346x260 seeds 0-3 15.72 -> 13.62 mm (13.00 / 18.22 / 16.35 /
    15.30 -> 11.01 / 15.76 / 14.41 / 13.30), seeds 4-7 16.79 -> 14.95 (every seed better), ARE 0.163 / 0.145 ->
    0.148 / 0.132 deg; 240x180 seeds 0-3 18.86 -> 18.11 mm. Bundled demos (``evpose track`` on
    ``maps/landing_map.ply``, ``evpose eval --align none``, ATE RMSE): ``landing`` 9.71 -> 10.00 mm,
    ``landing_fast`` 18.20 -> 19.06 mm, ``landing_dynamic`` 12.27 -> 10.84 mm. The EKF backend on the 2 s sets
    (``full:ekf``) 6.58 / 6.00 / 7.31 / 8.54 -> 6.05 / 5.36 / 7.41 / 7.41 mm: the graph, ahead on all four before,
    is ahead on two (346x260 seeds 4-7, 240x180 seeds 0-3). CPU per update +0.02-0.04 ms (seed 0, 346x260, paired
    runs, median 2.6-3.1 ms at load ~3)."""
    grazing_on_lead_px: float = field(default=0.0, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``on_lead_px`` of the grazing points (see ``grazing_max_cos``), pixels."""
    grazing_off_lead_px: float = field(default=-0.28, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``off_lead_px`` of the grazing points (see ``grazing_max_cos``), pixels."""
    crease_radius_m: float = field(default=0.02, metadata={"min": 0.0, "max": 0.1, "step": 0.005, "unit": "m"})
    """Points with a point of another region within this distance whose surface normal makes an absolute cosine
    below 0.5 with their own (a crease between two planes: a box's top and side) take ``crease_on_lead_px`` /
    ``crease_off_lead_px``, the other points whose edge the camera sees past ``beyond_off_lead_px``, unless grazing
    (see ``grazing_max_cos``), metres (0 = off: ``on_lead_px`` / ``off_lead_px`` for every face-on point).

    Measured (session 17, ``/tmp/s17/edgeclass7/classes.py``, ``rim.py`` on ``grazing_max_cos``'s per-event offsets
    from the true edges, seeds 0 / 1 / 4 at 346x260 and 240x180): 93 % of the built map's points are creases at 2 cm
    (half the face-on events: box tops at 0.4 / 1.5 m), the rest mostly the 0.15 m steps' tops and ground edges with
    a known brightness sign. Face-on OFF events of crease points trail by -0.256 to -0.267 px in all six runs (convex
    and concave alike within 0.01), of the others by -0.003 to -0.074, those split again: where the camera sees past
    the edge (the map's outward edge normal towards the camera centre; 4-6 % of the face-on OFF events) they *lead*
    by +0.30 / +0.41 / +0.37 px (346x260 seeds 0 / 4, 240x180 seed 0: a low step's unmapped riser shows beyond its top
    edge and fires its own OFF events there), the rest trail by -0.08 to -0.11. Face-on ON events: creases -0.04 to
    -0.07, the others -0.15 to -0.32 px. Grazing OFF: creases -0.28 to -0.29 (as ``grazing_off_lead_px``).

    ``full``, 2 s landing, mean ATE of 346x260 seeds 0-3 / 4-7 and 240x180 seeds 0-3 / 4-7 (the four sets' average;
    ``/tmp/s17/edgeclass7/run.py``, ``sets.sh``, ``run_beyond.py``): off 6.12 / 5.28 / 7.35 / 7.51 (6.565); the
    measured face-on OFF leads crease -0.26 / other -0.05 5.84 / 5.14 / 7.69 / 7.57 (6.562), with the ON ones (-0.06
    / -0.18) 6.11 / 5.06 / 7.84 / 7.54 (6.636); half the OFF split (-0.22 / -0.11) 5.95 / 5.09 / 7.45 / 7.52 (6.503),
    at 1 cm 5.93 / 5.08 / 7.55 / 7.53 (6.523), with half the ON split 5.89 / 5.08 / 7.60 / 7.46 (6.507); half the OFF
    split and the points seen past their edge at +0.15 / +0.35 / **+0.5** / +0.7 px: 5.95 / 5.01 / 7.51 / 7.40
    (6.467), 5.85 / 4.92 / 7.35 / 7.38 (6.378), **5.84 / 4.76 / 7.29 / 7.36 (6.313)**, 5.78 / 4.71 / 7.42 / 7.62
    (6.385); the full OFF split with +0.35 5.86 / 4.91 / 7.48 / 7.49 (6.436); +0.5 alone (every other face-on OFF
    point at -0.17) 5.95 / 5.03 / 7.09 / 7.67 (6.434). With the defaults, ``on_lead_px`` -0.09 (the face-on ON
events off a crease) 5.72 / 4.88 / 7.41 / 7.30 (6.324), the radius 3 cm 5.95 / 4.82 / 7.45 / 7.25 (6.371); the EKF
backend (``full:ekf``) 6.05 / 5.36 / 7.41 / 7.41 -> 5.88 / 4.79 / 7.50 / 7.24 (6.35), the graph ahead on three sets
(all but 240x180 seeds 4-7). The field's matching split
    (``registration.fused_crease_off_trail_px``) did not help. With the defaults: ARE 0.064 / 0.065 / 0.079 / 0.085
    -> 0.061 / 0.058 / 0.081 / 0.080 deg; 3 s landings (``run3.py``) at 346x260 seeds 0-3 13.62 -> 12.16 mm (11.01 /
    15.76 / 14.41 / 13.30 -> 9.88 / 14.67 / 12.72 / 11.36), seeds 4-7 14.95 -> 13.31 (11.35 / 17.85 / 18.85 / 11.74 ->
    9.93 / 15.83 / 17.41 / 10.06), but at 240x180 seeds 0-3 18.11 -> 18.83 (21.41 / 17.12 / 13.83 / 20.09 -> 23.12 /
    18.50 / 13.78 / 19.93); bundled demos (``evpose track`` on ``maps/landing_map.ply``, ``evpose eval --align
    none``, ATE RMSE): ``landing`` 10.00 -> 9.95 mm, ``landing_fast`` 19.06 -> 18.56, ``landing_dynamic`` 10.84 ->
    10.43."""
    crease_on_lead_px: float = field(default=0.0, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``on_lead_px`` of the face-on crease points (see ``crease_radius_m``), pixels."""
    coarse_on_lead_px: float = field(default=-0.07, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Added to ``crease_on_lead_px`` and ``grazing_on_lead_px`` on a sensor whose pixel subtends at least
    ``coarse_on_lead_min_pixel_mrad``, pixels (negative: the ON events of those points are taken behind their edge).

    Measured (session 33, ``/tmp/s33/swing33/``: ``decomp.py`` with ``DUMP=1`` registers every update from the true
    pose and writes each associated event's signed offset from its point's edge at the event's time, ``dumpana.py``;
    240x180 2 s landing seeds 0-1, the built map, the tracker's gate): the ON events of crease points sit -0.055 /
    -0.055 / -0.074 / -0.099 px behind their edge (0-50 / 50-500 / 500-1000 / 1000-2000 ms), those of grazing crease
    points -0.061 / -0.057 / -0.086 / -0.106, per point -0.054 to -0.120 px on average (tops and feet, both seeds),
    where their leads say 0; the OFF classes sit within 0.05 px of theirs. (Session 17 had measured face-on ON events
    at -0.06 to -0.08 px against the true edges.) Both ON leads at -0.07 (``full`` from ground truth, the CLI path,
    ``run.sh`` / ``run2.sh``, ``cmp.py``, ``demo.sh``, ``demcmp.py``; paired against 0 / 0): 240x180 2 s seeds 0-23
    5.568 -> 5.398 mm (-0.17 +- 0.11, 14 of 24 better), ARE 0.0667 -> 0.0602 deg; held-out seeds 24-47 6.091 ->
    5.815 (-0.28 +- 0.13, 14 of 24), ARE 0.0707 -> 0.0636 (0-47: 5.829 -> 5.606, -0.22 +- 0.08); 3 s landing at
    240x180 seeds 0-7 15.889 -> 14.495 (-1.40 +- 0.44, 7 of 8), ARE 0.1055 -> 0.1143; 346x260 2 s seeds 0-23 4.529 ->
    4.516 (-0.01 +- 0.09, 13 of 24), seeds 24-31 5.261 -> 4.961 (-0.30 +- 0.15, 6 of 8); but the bundled 346x260 demos
    (``evpose track demo_data/X.h5 --map maps/landing_map.ply``, ``evpose eval --align none``) ``landing`` 6.615 ->
    6.506 mm, ``landing_fast`` 9.357 -> 9.957, ``landing_dynamic`` 5.697 -> 6.270, and alike at -0.069 / -0.071
    (6.585 / 6.488, 9.912 / 10.016, 6.047 / 6.320): not chaos. Hence on coarse sensors only, where the issue's 240x180
    target is; the 346x260 figures and the demos are those of 0. It does not remove the registrations' swing along the
    tilt / shift ridge early in the flight (docs/measurements.md, session 33): +0.01 px on every ON lead moves that
    ridge by -0.15 to +0.13 mm."""
    coarse_on_lead_min_pixel_mrad: float = field(default=5.0, metadata={"min": 0.0, "max": 100.0, "step": 0.1, "unit": "mrad"})
    """Pixel angle (``1 / fx``) from which ``coarse_on_lead_px`` applies, milliradians (0 = never): the simulated
    240x180 camera's pixel subtends 5.83 mrad, the 346x260 one's and the demos' 4.05."""
    crease_off_lead_px: float = field(default=-0.22, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``off_lead_px`` of the face-on crease points (see ``crease_radius_m``, which gives the figures), pixels.

    Session 31 (``/tmp/s31/rim31/run2.py``, ``ana2.py``; ``full``, 2 s landing from ground truth, seeds 0-23, the map
    with :attr:`evpose.mapping.build.MapBuildConfig.crease_refit` on): -0.16 instead of -0.22 at 240x180 5.927 -> 5.760 mm
    (-0.17 +- 0.05, 17 of 24 better; seeds 0-11 5.651 -> 5.436, 12-23 6.202 -> 6.084), ARE 0.0732 -> 0.0694 deg, the
    along-motion bias +2.76 -> +2.23 mm; at 346x260 4.582 -> 4.595 (+0.01 +- 0.04), ARE 0.0560 -> 0.0567; demos (346x260)
    ``landing`` 6.57 -> 7.04 mm, ``landing_fast`` 10.11 -> 9.91, ``landing_dynamic`` 5.91 -> 6.57. So it would have to
    change on coarser sensors only (as ``angle_reference_pixel_mrad`` does for the gate): the option since (offlead31,
    ``lead_reference_pixel_mrad``, ``crease_off_lead_pixel_exponent``; off: the 3 s landing at 240x180 loses with it).
    All three OFF leads halved (-0.055 / -0.11 / -0.14) at 240x180: 6.352 mm (the height and sideways errors grow).
    Session 31 (offlead31): may shrink on coarser sensors only, figures at ``crease_off_lead_pixel_exponent``."""
    lead_reference_pixel_mrad: float = field(default=4.05, metadata={"min": 0.0, "max": 100.0, "step": 0.01, "unit": "mrad"})
    """On a sensor whose pixel subtends more than this angle (``1 / fx``), ``crease_off_lead_px`` shrinks by ``(this /
    pixel) ** crease_off_lead_pixel_exponent``, milliradians (0 = never). The leads were tuned on the simulated 346x260
    70 deg camera (4.05 mrad: unchanged there, as on the bundled demos); its 240x180 sibling has 5.83 mrad."""
    crease_off_lead_pixel_exponent: float = field(default=0.0, metadata={"min": 0.0, "max": 4.0, "step": 0.1, "unit": "ratio"})
    """Power of ``lead_reference_pixel_mrad / pixel`` that ``crease_off_lead_px`` shrinks by on coarser sensors, ratio
    (0, the default, = the same pixels at every resolution; 1 keeps the lead's angle: -0.22 -> -0.153 px at 240x180).
    Off because the 3 s landing at 240x180 loses what the 2 s one gains (below).

    Session 31 (offlead31; ``/tmp/s31/offlead31/run.py``, ``q1.sh`` / ``q2.sh``, ``cmp.py``, results ``out/``; ``full``,
    2 s landing from ground truth, the default map (``crease_refit`` on), mean ATE mm, paired change +- its standard
    error, seeds better, ARE deg; the defaults' seeds 0-23 are rim31's ``Lcr`` run, which this checkout reproduces bit
    for bit on seed 0). 346x260 (4.047 mrad) and the bundled demos are unchanged by construction (``evpose track
    demo_data/landing.h5 --map maps/landing_map.ply`` still hashes ``a7cd2061617be315``). At 240x180 (5.835 mrad),
    exponent 0 (the defaults) / 1 (-0.153 px) / 2 (-0.106) / 3 (-0.073), and -0.16 px set by hand (rim31's):

    - seeds 0-23: 5.927 / 5.716 (-0.21 +- 0.07, 15 of 24) / 5.735 (-0.19 +- 0.09, 16) / 5.700 (-0.23 +- 0.12, 15) /
      5.760 (-0.17 +- 0.05, 17); ARE 0.0732 / 0.0689 / 0.0665 / 0.0652 / 0.0694; seeds 0-11 / 12-23 at exponent 1
      5.651 / 6.202 -> 5.387 / 6.045.
    - held-out seeds 24-35: 7.202 / 6.934 (-0.27 +- 0.15, 9 of 12) / 6.799 (-0.40 +- 0.21, 9) / 6.785 / 7.095 (-0.11
      +- 0.12, 7); ARE 0.0913 / 0.0841 / 0.0802 / 0.0770 / 0.0852.
    - seeds 0-35 pooled: 6.352 / 6.122 (-0.23 +- 0.07, 24 of 36) / 6.090 (-0.26 +- 0.09, 25) / 6.062 (-0.29 +- 0.11, 25).
    - held-out seeds 36-47 (chosen after the above; exponent 0 / 1 / 2): 6.522 / 6.371 (-0.15 +- 0.07, 10 of 12) /
      6.430 (-0.09 +- 0.11, 8); ARE 0.0767 / 0.0737 / 0.0722. Seeds 24-47 at exponent 1 6.862 -> 6.652 (-0.21 +-
      0.08, 19 of 24), seeds 0-47 6.395 -> 6.184 (-0.21 +- 0.05, 34 of 48); exponent 2 over 0-47 6.175 (-0.22 +- 0.08,
      33 of 48).
    - 3 s landing (with the turn) seeds 0-7 (``q3.sh`` / ``q4.sh``, exponent 0 / 0.5 / 1 / 2): 16.991 / 17.714 /
      18.093 (+1.10 +- 0.24, 0 of 8 better) / 19.380 mm, ARE 0.1145 / 0.1170 / 0.1204 / 0.1320 deg; per seed 11.39
      14.64 14.75 18.89 17.77 20.78 19.45 18.27 -> (1) 12.55 15.84 15.53 19.98 17.93 21.20 21.55 20.18: every seed worse,
      more so the smaller the lead (as session 17 found the crease leads costing this landing at 240x180, see
      ``crease_radius_m``).
    Per seed (exponent 0 -> 1), seeds 24-35: 7.86 7.65 6.23 7.24 9.10 9.15 4.68 5.18 7.88 8.08 6.87 6.51 -> 7.51 7.19
    6.42 7.64 8.72 8.75 5.47 4.98 6.77 7.45 6.09 6.22; seeds 0-23 at 1: 7.07 5.43 7.47 4.24 6.38 3.40 4.99 4.18 5.76
    4.07 3.87 7.78 5.43 4.25 7.21 4.16 5.29 4.59 7.94 5.37 8.83 5.00 7.47 7.00. The smaller leads lower the ARE
    steadily on the 2 s landing; its ATE is flat from exponent 1 to 3 on seeds 0-23 with a growing per-seed spread, so
    1 (the lead the same angle at every pixel size) is the value to take if only the 2 s landing counts. The 3 s
    landing wants the lead as it is at 240x180, so the leads trade the 2 s flight's along-motion bias against what
    the 3 s one needs (its turn), and this stays off until that is understood."""
    covered_foot_off_lead_px: float = field(default=0.0, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Added to the OFF lead of a vertical face's foot (a point at a vertical region's bottom, or beside one within
    ``crease_radius_m``, along a horizontal-ish edge) while the face's image lies behind the foot along its image
    motion (the face's nearer top rim sweeping it shut towards the foot: a "covered" foot) and spans less than
    ``covered_foot_max_width_px``, pixels (0 = off). :mod:`evpose.tracker.covered_feet` has the offsets measured at the
    truth; costs two projections per used foot per registration (``/tmp/s34/rim34/timing.py``: see the module).

    Off: it is not a property of the class. Session 34 (``/tmp/s34/rim34/``: ``run.sh``, ``cmp.py``, ``demo.sh``,
    ``demcmp.py``, ``cfg/``; ``full`` from ground truth, the CLI path on the cached landings, paired against main's
    defaults, mean ATE mm, change +- standard error, seeds better, ARE deg). +0.1 px, faces up to 100 px
    (``cw10``): 240x180 2 s seeds 0-23 5.255 -> 5.104 (-0.150 +- 0.065, 17 of 24), ARE 0.0603 -> 0.0585; held-out
    seeds 24-47 5.652 -> 5.532 (-0.120 +- 0.067, 16 of 24), ARE 0.0629 -> 0.0608; but the 3 s landing at 240x180
    seeds 0-7 13.512 -> 17.401 (+3.89 +- 0.48, 0 of 8; the loss builds from 0.5 to 2 s, over that flight's first
    leg, ``errt.py``) and 346x260 2 s seeds 0-23 4.279 -> 4.366 (+0.087 +- 0.057, 10 of 24), ARE 0.0504 -> 0.0510.
    The 3 s flight (6.6 m up, another path) sees other covered feet, whose OFF events sit -0.32 / -0.34 px (ground
    side, seeds 0 / 1, 0-0.6 s; lead -0.22) and -0.33 / -0.32 (the face's own, lead -0.28): behind their leads where
    the 2 s flight's sit ahead (``ana11.py`` with ``DUR=3``). Also measured on the 2 s landing seeds 0-23: +0.15 px
    5.130 (-0.125 +- 0.068, 16 of 24); +0.1 on the ground's side only (``covered_foot_wall_side`` False) 5.188 (-0.067
    +- 0.040, 15 of 24); -0.35 px on faces narrower than 12 px (one crate's foot early in the flight sits there)
    5.513 (+0.258 +- 0.078, 7 of 24: the other narrow covered feet sit +0.07 to +0.14 px ahead of their leads from
    0.6 s on). Learning the lead online instead (a prototype, not kept: ``/tmp/s34/rim34/patch/learned_lead.diff``;
    each accepted update moves it by 0.05 of the covered feet's mean event distance beyond it, signed along their
    motion, at the registered pose, from 0): 2 s seeds 0-23 5.290 (+0.035 +- 0.041, 12 of 24), 3 s seeds 0-7 13.184
    (-0.33 +- 0.26, 6 of 8); it learns -0.01 to -0.03 px on the 2 s flight (seed 0, ``learnlog.py``), where the truth
    says +0.1: at the registered pose the events' ridge error has already taken up the feet's offset (the gauge the
    per-point offsets cannot see either); on the 3 s flight -0.04 to -0.15 px, the truth's direction. Leaving the
    covered feet's OFF events out (this lead at +2.0 px, beyond the gate: ``cfg/cdrop.yaml``; at the truth the 2 s
    ridge step +4.44 -> +2.63 mm over 50-600 ms, ``ana13.py``): 2 s seeds 0-23 5.291 (+0.036 +- 0.063, 11 of 24), 3 s
    seeds 0-7 14.696 (+1.18 +- 0.40, 1 of 8): the ground-level events hold more than their offset costs."""
    covered_foot_max_width_px: float = field(default=100.0, metadata={"min": 0.0, "max": 1000.0, "step": 0.5, "unit": "px"})
    """Widest projected face (along the foot's image normal) for which ``covered_foot_off_lead_px`` applies, pixels: a
    0.4 m crate's side spans 4-12 px at 240x180 from 4-5 m up, a 2.2 m building's 24-80 px."""
    covered_foot_wall_side: bool = True
    """With ``covered_foot_off_lead_px``: the face's own points at its foot take it too; False = only the ground's
    points beside the foot (figures there)."""
    beyond_off_lead_px: float = field(default=0.5, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``off_lead_px`` of the face-on points off a crease whose edge the camera sees past (their outward edge normal
    points towards the camera centre: a low step's unmapped riser shows beyond its top edge), with ``crease_radius_m``
    on, pixels."""
    follower_crossings: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "crossings"})
    """An event whose pixel fired an event of the same polarity less than this many of its edge's pixel-crossing
    times before (``1 / v``, ``v`` the edge's normal image speed from the motion twist, pixels per second) follows that
    event in one passage of the edge and takes ``follower_on_lead_px`` / ``follower_off_lead_px`` on top of its
    point's lead, any other ``first_on_lead_px`` / ``first_off_lead_px``, crossing times (0 = off: the point's lead
    alone). The pixels' latest event times (every event of the step, kept or not) are part of the state.

    Why (session 32, ``/tmp/s32/edge32/offsets.py``, ``ana2.py``, ``ana3.py``: every event of 1 ms windows every 5 ms
    within 1.5 px of one visible true edge and 3 px of any other, its signed offset from that edge at its own time
    along the edge's image motion, ground-truth pose, 2 s landing): the offset does not follow the edge's normal speed
    (240x180 seed 1, OFF by speed quintile 3-96 / ... / 187-295 px/s -0.175 / -0.177 / -0.191 / -0.220 / -0.204 px,
    ON -0.119 / -0.067 / -0.060 / -0.052 / -0.146; 346x260 seed 0 alike; a constant delay would make it fall with the
    speed), nor the pixel size (mean ON / OFF -0.089 / -0.194 px at 240x180, -0.087 / -0.201 at 346x260), but it does
    follow the event's place in its pixel's burst: the first event of a passage (no same-polarity event of the pixel
    within one crossing time before) ON +0.057 / OFF -0.136 px, the ones after it ON -0.307 / OFF -0.415 px (346x260:
    +0.058 / -0.129, -0.308 / -0.408; 3 s landing at 240x180: -0.027 / -0.210, -0.302 / -0.421), the within-class spread
    ON 0.283 -> 0.220 px. A pixel-integrated edge crosses the log threshold early in its first event (ON) and its
    later events come with the edge past the pixel centre. Against the events' own copy of the map at the true pose
    (``diag2.py``, 240x180 seed 0, the tracker's associated events) the same split: ON first +0.076 / followers -0.295
    px, OFF -0.105 / -0.358 px.

    Off because it costs (``run.sh``, ``cmp.py``, ``bias.py``; ``full``, 2 s landing from ground truth at 240x180, seeds
    0-23, mean ATE 5.984 mm, ARE 0.0736 deg): these deltas (1 crossing) 7.452 mm (+1.47 +- 0.25, 3 of 24 better), ARE
    0.1145; the deltas measured against the map (+0.08 / -0.30 / +0.07 / -0.21) 7.603 (+1.62 +- 0.32, 4 of 24), ARE
    0.1127. The along-motion bias stays (camera-frame mean error x / y / z +2.80 / -0.35 / -1.12 -> +2.82 / -4.04 /
    -2.19 and +2.01 / -4.07 / -1.80 mm): a sideways bias appears instead. The class leads above were tuned with the
    burst mixed in, and the along-motion bias is not theirs (see ``combine_convex``)."""
    first_on_lead_px: float = field(default=0.15, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Added to an ON event's lead when it is the first of its pixel's passage (see ``follower_crossings``), pixels:
    the measured first-event mean less the ON mean (+0.057 + 0.089)."""
    follower_on_lead_px: float = field(default=-0.22, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """Added to an ON event's lead when it follows another (see ``follower_crossings``), pixels (-0.307 + 0.089)."""
    first_off_lead_px: float = field(default=0.06, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """As ``first_on_lead_px`` for OFF events, pixels (-0.136 + 0.194)."""
    follower_off_lead_px: float = field(default=-0.22, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """As ``follower_on_lead_px`` for OFF events, pixels (-0.415 + 0.194)."""
    iterations: int = field(default=3, metadata={"min": 1, "max": 20, "step": 1, "unit": "iterations"})
    """Gauss-Newton steps on one association, iterations (2: 6.03 mm against 6.08, replacing, 346x260 (3 px); combined
    (2 px): 6.44 / 5.92 and 7.26 / 8.55 mm, ~0.03 ms less)."""
    prior_residual_px: float = field(default=0.5, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "px"})
    """Typical distance of one event from its edge, which converts registration's isotropic pose prior (``prior_*``,
    towards the prediction) into the events' units; 0 = no prior, pixels (0: 6.23 mm against 6.08; session 29, 240x180
    seeds 0-7, 0.3: 6.932 mm against 6.955; session 37, ``full`` at 240x180 2 s seeds 0-23, the
    CLI path paired against the defaults, ``/tmp/s37/rt37/run.sh``, 0.35: 5.060 -> 5.135 mm, +0.076 +- 0.055, 10 of 24 better)."""
    min_events: int = field(default=100, metadata={"min": 6, "max": 100000, "step": 10, "unit": "events"})
    """Fewer associated events than this: the field registration stands alone, events."""
    skip_painted: bool = True
    """Leave the map's painted (albedo) edges out: the built map has them ~10 mm off (936 of its 979 painted points
    more than 1.5 mm from the true edge, seed 0), which the field's smoothing and robust loss tolerate but the
    events do not (346x260 seeds 0-3, replacing, 3 px association radius: 9.99 mm with them against 6.08)."""
    skip_wall_feet: bool = True
    """Leave the points at the foot of a wall out (:mod:`evpose.tracker.wall_occlusion`): seen over the wall they
    take the rim's events (6.32 mm with them against 6.08)."""
    offset_gain: float = field(default=0.3, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Share of each update's gauge-free per-point offset (its events' mean distance from its edge line, the part a
    pose change explains taken out) that the events' copy of the map moves by (0 = the map as built), ratio.

    346x260 seeds 0-3, replacing, ``covariance_scale`` 300: 0.1 / 0.3 / 0.5 gave 6.26 / 6.08 / 6.15 mm; 240x180
    (``covariance_scale`` 100) 0 (the map the field reads, with its own offsets) / 0.1 / 0.3 / 0.6: 8.56 / 9.05 /
    8.76 / 8.80 mm. Seed 0 at 346x260 with an oracle mask (only points within 1.5 mm of the true edges): 8.19 ->
    6.26 mm. Points rejected instead (by their events' mean distance, per update or averaged): no better.

    Session 38 (``full``, 240x180 2 s seeds 0-23, CLI path paired against main's defaults 4.982 mm, ``/tmp/s38/tr38``
    ``run.sh``, ``cmp.py``): 0 / 0.03 / 0.1 / 0.6 gave +0.046 +- 0.071 / +0.009 +- 0.059 / +0.022 +- 0.048 / +0.040 +-
    0.035 mm (11 / 11 / 12 / 9 of 24 better); 0 on held-out 24-47 -0.004 +- 0.057 (10 of 24), 346x260 -0.010 +- 0.052
    (13 of 24), 3 s seeds 0-7 -0.12 +- 0.16 (5 of 8): a slow running mean, or none, does not differ. Why (``resid.py``,
    ``ana.py``: each registration's events linearised at the true pose against this learned map, seeds 0-2, 24, 25):
    what a point's events leave there is 0.03-0.05 px per point and not static (split-half r 0.11-0.43; against the
    true edges, per edge, 0.84-0.95), and a second gauge-free learner on top leaves the registrations' slow
    tilt-vs-sideways bias at the truth as it is (2.2-3.3 mm). Only corrections that know the truth (the pose-like part,
    which the events at the estimated pose cannot show, since the fused pose passes that slow bias through) remove
    it: each point's whole-run mean at the truth, in hindsight, leaves 0.7-1.0 mm; a running mean at the truth cuts
    only 0.1-0.3 mm."""
    offset_min_weight: float = field(default=3.0, metadata={"min": 0.5, "max": 100.0, "step": 0.5, "unit": "events"})
    """A point learns only from an update where its events' robust weights sum to at least this, events (1.5: 6.32 mm
    against 6.38, 346x260 seeds 0-3, within the seeds' spread)."""
    offset_clip_px: float = field(default=1.0, metadata={"min": 0.05, "max": 5.0, "step": 0.05, "unit": "px"})
    """A point whose events' mean distance is larger than this takes no part in that update, pixels (0.5: 6.12 mm
    against 6.08; 2.0: 6.43 mm against 6.38, combined, 2 px association radius)."""
    offset_max_m: float = field(default=0.05, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest distance a point may move from the map's position, metres. Session 18 (seeds 0-7, 240x180 / 346x260,
    7.325 / 5.30 mm): 0.005 7.45 / 5.37 mm; no learning at grazing points (``grazing_max_cos``, whose ON events'
    lead the offsets take up, 5-14 mm off the true edges) 7.43 / 5.50; ``offset_gain`` 0 7.59 mm at 240x180."""
    contrast: ContrastLeadConfig = field(default_factory=ContrastLeadConfig)
    """Leads of the points whose pixels fire one event per passage of their edge (:mod:`evpose.tracker.contrast_leads`;
    on since session 42)."""
    lag: EventLagConfig = field(default_factory=EventLagConfig)
    """Leads growing with each edge's normal image speed (:mod:`evpose.tracker.event_lag`; off by default)."""
    edge_clusters: EdgeClusterConfig = field(default_factory=EdgeClusterConfig)
    """Each edge's events sharing one offset in the normal equations (:mod:`evpose.tracker.edge_clusters`; off)."""


def scaled_to_pixel(config: EventRegistrationConfig, pixel_mrad: float) -> EventRegistrationConfig:
    """``config`` with ``gate_px``, ``huber_px`` and ``covariance_scale`` shrunk for a sensor whose pixel subtends
    ``pixel_mrad`` (see ``EventRegistrationConfig.angle_reference_pixel_mrad``), and ``crease_off_lead_px`` (see
    ``lead_reference_pixel_mrad``), with ``coarse_on_lead_px`` added to the crease and grazing ON leads on a coarse
    sensor (``coarse_on_lead_min_pixel_mrad``); ``config`` itself at or below every reference."""
    out = config
    ref = float(config.angle_reference_pixel_mrad)
    if ref > 0 and pixel_mrad > ref:
        k = (ref / float(pixel_mrad)) ** float(config.angle_pixel_exponent)
        c = (ref / float(pixel_mrad)) ** float(config.covariance_pixel_exponent)
        out = dataclasses.replace(out, gate_px=float(config.gate_px) * k, huber_px=float(config.huber_px) * k,
                                  covariance_scale=float(config.covariance_scale) * c)
    ref = float(config.lead_reference_pixel_mrad)
    exponent = float(config.crease_off_lead_pixel_exponent)
    if ref > 0 and pixel_mrad > ref and exponent != 0:  # the reference sensor and finer ones keep the value as set
        out = dataclasses.replace(out, crease_off_lead_px=float(config.crease_off_lead_px) * (ref / float(pixel_mrad)) ** exponent)
    on, at = float(config.coarse_on_lead_px), float(config.coarse_on_lead_min_pixel_mrad)
    if on != 0 and at > 0 and pixel_mrad >= at:
        out = dataclasses.replace(out, crease_on_lead_px=float(out.crease_on_lead_px) + on,
                                  grazing_on_lead_px=float(out.grazing_on_lead_px) + on)
    return out
