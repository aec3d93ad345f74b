"""Registration of the step's events themselves against the projected map edges, each at its own timestamp (``full``).

The time surface's distance-field minimum trails a moving edge by a speed-dependent amount, and what
:mod:`evpose.tracker.registration` leaves of that trail (0.1-0.3 px, shared by whole edges and slow) is what the
fusion turns into tilt-vs-sideways error. An event has no such lag: it fired when the edge crossed its pixel. Here
each kept event of the step is associated with the nearest used map point (projected at the field registration's
pose, within ``association_radius_px``, of a polarity the point may fire), and its residual is its signed distance
along the point's projected edge normal from the point's projection *at the event's timestamp* (the pose moved back
along the motion twist). A few robust Gauss-Newton steps from the field registration's pose (which gave the basin)
find the events' own optimum, which is combined with the field registration by their covariances.

The events read the map without the field's smoothing, so the map's own errors show: painted edges (~10 mm off in
the built map) and wall feet are left out, and the other points slide along their edge normals by what a pose change
does not explain (gauge-free, as :mod:`evpose.tracker.edge_offsets` does with the field), in a copy of the map only
the events read.

Measured (2 s moderate landing from ground truth, built map, ``full``, mean ATE mm of seeds 0-3 / 4-7 at 346x260 and
240x180): the field alone 7.77 / 7.95 and 8.11 / 10.46 (smoothed offline 4.26 / 3.75 and 5.48 / 7.82); with these
defaults 6.38 / 5.91 and 7.25 / 8.49 (smoothed 4.12 / 2.94 and 4.52 / 5.98), ARE 0.066 / 0.068 and 0.076 / 0.088 deg
(was 0.077 / 0.081 and 0.093 / 0.105), no update lost. Bundled 346x260 demos (``evpose eval --align none``, ATE RMSE):
``landing`` 15.81 -> 9.71 mm, ``landing_fast`` 23.81 -> 18.20 mm, ``landing_dynamic`` 15.64 -> 12.27 mm (with a 3 px
association radius 9.42 / 14.28 / 11.61 mm). Where the gain comes from, 346x260: with the simulator's true edges as
the map, replacing the field's pose by the events' (no offsets, no masks, 3 px) took ``full`` seeds 0-3 from 7.30
to 6.19 mm (seed 0 8.46 -> 6.14), and the fused error's mean per camera axis went from -1.48 / -2.62 / 3.86 to 0.04 /
0.14 / 0.43 mm (seed 0); on the built map the same gave 16.1 mm (seed 0) until the painted points were left out.
CPU at 346x260 (seed 0, thread time, load ~7): 0.58 ms median per update in a run (0.3 ms called again and again on
one update's inputs: the association, each of the 4 passes over ~900 events ~0.03 ms, the rest Python), the learning
0.05 ms; the whole ``full`` update 3.4-4.7 -> 4.4-6.0 ms median (3 alternated rounds, same process). Hot, one
update's inputs called again and again (seed 0, 865 points, 1265 events, 938 associated): association 33 us, each
pass 26 us, ~400 us per call over 200 consecutive updates: the rest is Python and gtsam around 5 numba calls. Session 13
(bit-identical: the kept events gathered and the associated ones compacted in the kernels, no numpy gathers, the
damped step, inverses and eigenvalues without numpy's wrappers, the association's test by selects): the 393 calls of
seed 0 at 346x260 replayed with their learning, CPU per call 0.40-0.44 -> 0.34-0.35 ms median; in a run the
association 86 us, the passes 36 / 33 / 28 / 26 us, the learning 20 us (thread time, load ~4).

What limits it now (session 12, ``full`` 346x260 seeds 0-3 unless said, 6.38 mm with these defaults; oracles from
the simulator's true edges, ``/tmp/s12/fullacc2/oracle.py``): the events' copy of the map moved along each point's
edge normal onto the true edges (painted points then included) gives 5.74 mm combined and 4.77 mm (ARE 0.053 deg)
with the events' pose replacing the field's; only its points more than 1 mm off so moved (9 % of them), replacing,
4.94 mm; only the painted ones, combined, 6.14 mm; at 240x180 6.45 combined / 5.88 replacing (against 7.25). So
the events' map sets the limit, and the offsets learned online do not find it: on the horizontal surfaces' points
they moved, the learned offsets correlate 0.43-0.48 with the true ones and cut their RMS only 1.56 -> 1.47 mm
(seed 0, end of the run; gain 0.05: 0.47, 1.55 -> 1.40 mm); counting the vertical faces' rims too, whose edge
normal lies nearly along the view ray, 0.13-0.15 and 2.5 -> 4.9 mm: those slide by centimetres and stop pulling,
which helps (learning only where a move along the normal shifts the image by at least 30 / 100 px/m instead of
the kernel's 5: 6.70 / 6.86 mm). Not better either: the offsets pooled, each update, over the points of the same
region with parallel edge normals within 3 / 6 / 12 cm (6.50 / 6.27 / 6.62 mm; 6 cm with gain 0.1 6.46); the
vertical faces' rims or vertical edges left out of the events (6.83 / 6.43 mm); the painted points entering the
events at the field refiner's positions (:mod:`evpose.tracker.map_refinement`, 4 mm RMS from the truth after
~40 updates against 11 mm as built) once refined in 10 / 30 updates (6.34 / 6.29 mm); the factor graph's AR(1)
registration error model (``fusion.registration_error_model`` ``ar1_whitened``, rho 0.95, innovation scale 0.5,
between scale 3): 5.72 mm (ARE 0.059) but seeds 4-7 6.18 against 5.91 and 240x180 7.23 against 7.25. Nor does
the factor graph gain on the EKF once the map is right: on the oracle map the EKF gives 5.71 mm combined (graph
5.74) and 4.78 replacing (graph 4.77): either backend passes the registrations' slow error through.

Session 14, not kept (``full`` mean ATE of seeds 0-3, 240x180 / 346x260, against 7.25 / 6.38 mm; scripts in
``/tmp/s14/fullacc/``). In the events' weakest directions (tilt against sideways shift) their normal equations
hold 0.1-5x the information of the pose prior towards the prediction (seed 0 at 240x180), so the prior sets
those directions of the pose the fusion gets: handing on the events' own optimum (the pose moved by
``H^-1 P e`` off the prior's pull, the covariance of ``H`` alone) gave 7.19 / 6.57 mm (240x180 seeds 4-7 8.32
against 8.49); the same for the field registration's isotropic prior 7.42 mm at 240x180, both 7.57. The events
of the step before registered too (each at its own timestamp): 7.49 / 6.66 mm, with ``covariance_scale`` 600
7.26 / 6.58. The events' variance along the optical axis scaled by 10 / 0.1 before combining: 9.53 / 8.25 mm at
240x180 (10: 8.37 at 346x260). With ``fusion.init_sigma_acc_bias_vertical`` 0.5 (240x180 6.74 mm):
``covariance_scale`` 100 / 1000 6.88 / 7.26 mm, ``registration.max_points`` 1500 6.79 mm. Fusing the two poses
as two factors instead of combining them is the same cost to first order (each scaled alike; the graph's robust
kernel never engages), so it was not run.

Session 15 (346x260 seeds 0-3 unless said; scripts ``/tmp/s15/regdrift/``): the registrations' slow errors are mostly
the prediction's, echoed, not a bias of the field's optimum. Inside closed-loop runs (seed 0, built and true-edge
maps), the field registration run again without its prior and to convergence stays where it starts: from the
prediction at the prediction's height error (camera z, 0.6-1.0 s: 5-10 mm, the fused pose 7-11 mm, the run's own
registration 6-10 mm), from the truth within 1-3.5 mm, from the prediction moved 20 mm up at +16 mm. Tilt against
sideways shift behaves alike; roll less (~20 mdeg). Starting the registrations from the truth (oracle; ``full`` 6.38
mm) gives 4.90 mm with their priors there too, 5.49 with the priors still at the prediction; only the tilt/sideways
components 5.33 (init only 5.84), only the height 6.02, only the roll 6.41: the roll drift costs nothing, the echo of
tilt and height does. The field's first-order (Gauss-Newton) information is 5-15 % of the second-order one its
covariance reports (the curvature of each point's own TDF minimum), so it claims what it only echoes. Not kept
(346x260 / 240x180 seeds 0-3, against 6.38 / 7.25 mm): the events registered first from the prediction and the field
from their pose (prior still at the prediction) 6.67 / 7.82; ``prior_residual_px`` 0 6.44 / 7.28; the covariance
without the priors' information (field and events) 6.43 (346x260); see also ``registration.second_order``,
``prior_translation_m``, ``convergence_cost_ratio`` and ``distance_field.coarse_blur_px``.

Session 16 (scripts ``/tmp/s16/echo7/``): the echo is not a trapped optimiser. Inside closed-loop runs (every 30th
update, ``costline.py``), the field registration converged without prior (50 iterations, no cost-ratio stop) from the
prediction (A) and from the truth (B) mostly reach the same minimum, 3-52 mm from the truth (346x260 seed 0 4-26 mm,
seed 2 6-39 mm, 240x180 seed 0 3-52 mm), and the truth costs more than that minimum at 35 of 39 probes; along the line
from A through the truth the mean cost per point changes by < 0.1 %. So the field's cost is flat in those directions
and its minimum is biased: a wider search finds that minimum, not the truth; the echo (early stop plus prior)
regularises towards the prediction, which is why full convergence is worse (``convergence_cost_ratio`` 0: 6.52 mm).
Its covariance is not what over-trusts it either (``secant.py``, seed 0): the truth lies within 0-1.9 of its claimed
standard deviations in every eigen-direction (17-42 mm in the weakest translation), and the cost's actual rise at +-3
of them is 0.2-0.9 of the claimed one in the weak directions, mostly 0.7-1.0 in the strong. The events behave alike
(``evland.py``): registered without prior to convergence from the field pose, the prediction or the truth they reach
the same minimum, 3-13 mm off the truth until 1.1 s and 15-110 mm / up to 1.8 deg after (seed 0, 346x260). Which
points hold the field's minimum away from the truth (``pointblame.py``, rho at the truth minus rho at A, summed over
every 10th update): the painted points 3.5-4x as much per point as the others (346x260 / 240x180 seed 0: 1.23 / 1.14
per mille per point against 0.35 / 0.27 for the others), but they are 13-15 % of the points: the map's accurate points
prefer the biased minimum too. Not kept (mean ATE mm, 346x260 seeds 0-3 / 4-7, 240x180 seeds 0-3 / 4-7, against 6.38 /
5.91 / 7.25 / 8.49): the field's information along each eigen-direction capped by the cost's measured rise at +-3
claimed standard deviations (floor 5 %) 6.22 / 5.62 / 7.40 / 8.86, at +-2 6.26 / - / 7.36 / -, at +-5 6.39 (346x260
seeds 0-3); the two weakest directions' information scaled by the square of the share of a one-standard-deviation
displaced start that the registration pulls back 6.37 (seeds 0-3); the events' Gauss-Newton passes 6 / 10 6.43 / 6.45
(seeds 0-3); the painted points' share of the field cost 0.5 / 0.3 6.42 / 6.40 (seeds 0-3; 0.3 at 240x180 7.76);
painted points held out of the field registration for their first 10 refined updates (as in ``stpe``, see
``map_refinement.register_after_updates``) 6.15 / 6.12 / 7.14 / 8.94, for ever 6.52 (seeds 0-3). The cap, as the
field's covariance scaled before combining (``combine``), trades 346x260 against 240x180 (mean of the four sets 7.01
mm with these defaults, 7.03 capped, 7.09 held out): the target needs information the field and the events' map do not
hold (the events' copy of the map moved onto the true edges: 4.77 mm, session 12).

Session 17 (``/tmp/s17/polbias7/``): the events' own bias against the true edges, split by polarity, speed, age and
the surface's view angle, is no smaller than the map's: OFF events of surfaces seen at a grazing angle trail their
edges by 0.28 px where face-on ones trail by 0.135 (``grazing_max_cos``, now on with the field's matching
``registration.fused_grazing_off_trail_px``; 2 s landing 6.38 / 5.91 / 7.25 / 8.49 -> 6.12 / 5.28 / 7.35 / 7.52 mm,
3 s landings at 346x260 15.72 / 16.79 -> 13.62 / 14.95 mm). Oracles (``oracle.py``, seeds 0 / 1 / 4, before this):
each point's own mean event offset from its true edge as its ON / OFF lead 6.43 -> 6.04 mm at 346x260 and 9.50 ->
9.48 at 240x180 (per-point means of >= 5 events measured at the truth in every 5th update, so noisy); each point's
mean offset from the built map, with offset learning off, 5.94 / 9.70 mm. The events' map moved onto the true edges
(session 12's oracle, combined, seeds 0-3): 5.74 -> 5.08 mm at 346x260 and 6.45 -> 6.10 at 240x180 with these leads.
Split again by the map point's edge class (``crease_radius_m``, ``/tmp/s17/edgeclass7/``): face-on OFF events of
creases trail ~0.26 px, those of the other points where the camera sees past their edge lead ~0.35 px, the rest trail
~0.1 px; half the crease split with the seen-past lead +0.5 px took the four 2 s sets to 5.84 / 4.76 / 7.29 / 7.36 mm
(6.565 -> 6.313).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gtsam
import numpy as np

from evpose.tracker.event_registration_kernels import _associate_nearest, _kept_events, _learn_offsets, _linearise_events
from evpose.tracker.grazing import crease_points, grazing_points
from evpose.tracker.lapack_calls import inv
from evpose.tracker.registration import _eigvalsh, _inv, _isotropic_information
from evpose.tracker.registration_kernels import _lm_step

_NO_POLARITY = np.zeros(0, np.int8)
_NO_TWIST = np.zeros(6)
_NO_TABLE = np.zeros((0, 0, 2), np.float32)
"""Placeholders of the kernels' optional inputs (never written)."""


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
    covariance_scale: float = field(default=300.0, metadata={"min": 0.001, "max": 100000.0, "step": 1.0, "unit": "ratio"})
    """Factor on the events' covariance ``(J^T W J)^-1 sigma^2`` (``sigma^2`` their weighted residual variance), ratio.

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
    gate_px: float = field(default=1.5, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Events farther than this from their point's edge line (at the current pose) take no part, pixels (2 px: 6.34
    mm against 6.08; seed 0 without the painted mask 0.7 / 1.0 px: 17.7 / 16.1 mm against 16.1)."""
    huber_px: float = field(default=0.5, metadata={"min": 0.01, "max": 10.0, "step": 0.05, "unit": "px"})
    """Huber scale on the events' distances, pixels (0.3: 6.04 mm against 6.08, replacing, 3 px association radius).

    With ``gate_px`` 1.0 (combined, 2 px): seeds 0-3 / 4-7 6.29 / 5.59 mm at 346x260 and 7.25 / 8.30 mm at 240x180
    (ARE 0.062 / 0.066, 0.072 / 0.086 deg), the demos 9.47 / 16.84 / 12.35 mm, but the EKF backend then beats the
    graph at 240x180 (7.22 / 8.18 mm, ARE 0.073 / 0.085 deg): not kept."""
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
    crease_off_lead_px: float = field(default=-0.22, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``off_lead_px`` of the face-on crease points (see ``crease_radius_m``, which gives the figures), pixels."""
    beyond_off_lead_px: float = field(default=0.5, metadata={"min": -2.0, "max": 2.0, "step": 0.01, "unit": "px"})
    """``off_lead_px`` of the face-on points off a crease whose edge the camera sees past (their outward edge normal
    points towards the camera centre: a low step's unmapped riser shows beyond its top edge), with ``crease_radius_m``
    on, pixels."""
    iterations: int = field(default=3, metadata={"min": 1, "max": 20, "step": 1, "unit": "iterations"})
    """Gauss-Newton steps on one association, iterations (2: 6.03 mm against 6.08, replacing, 346x260 (3 px); combined
    (2 px): 6.44 / 5.92 and 7.26 / 8.55 mm, ~0.03 ms less)."""
    prior_residual_px: float = field(default=0.5, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "px"})
    """Typical distance of one event from its edge, which converts registration's isotropic pose prior (``prior_*``,
    towards the prediction) into the events' units; 0 = no prior, pixels (0: 6.23 mm against 6.08)."""
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
    6.26 mm. Points rejected instead (by their events' mean distance, per update or averaged): no better."""
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


class EventRegistration:
    """Registers the step's events (see the module); its state is the learned per-point offsets."""

    def __init__(self, config: EventRegistrationConfig, width: int, height: int, points: np.ndarray, tangents: np.ndarray,
                 edge_normal: np.ndarray, skip: np.ndarray | None = None, plane_normal: np.ndarray | None = None,
                 region_id: np.ndarray | None = None):
        """``points`` (N, 3) the map (copied), ``tangents`` (N, 3) its unit edge directions and ``edge_normal`` (N, 3)
        its edge normals (zero = unknown: such points take no events), ``skip`` (N,) bool points left out,
        ``plane_normal`` (N, 3) the surfaces' unit normals (zero = unknown; None = none known) for ``grazing_max_cos``,
        ``region_id`` (N,) their surface regions (-1 = none; None = none known) for ``crease_radius_m``."""
        self.config = config
        self._base = np.array(points, dtype=np.float64, order="C")
        self.points = self._base.copy()
        """The map the events are registered against: the built map plus the learned offsets."""
        n = np.asarray(edge_normal, dtype=np.float64)
        self._normals = np.ascontiguousarray(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12))
        self._tangents = np.array(tangents, dtype=np.float64, order="C")
        self._tangents[~np.any(n != 0, axis=1)] = 0.0
        if skip is not None:
            self._tangents[np.asarray(skip, np.bool_)] = 0.0  # no edge direction: such points take no events
        self._plane_normals = None if plane_normal is None else np.array(plane_normal, dtype=np.float64, order="C")
        self._crease = None
        if float(config.crease_radius_m) > 0 and plane_normal is not None and region_id is not None:
            self._crease = crease_points(self._base, self._plane_normals, region_id, float(config.crease_radius_m))
        self.offsets = np.zeros(self._base.shape[0])
        """Learned offset of each map point along its unit edge normal, metres."""
        self._width, self._height = int(width), int(height)
        self._last = None
        self.last_events = 0
        """Events associated with a point at the last :meth:`refine`."""

    def snapshot(self) -> np.ndarray:
        return np.copy(self.offsets)

    def restore(self, state: np.ndarray) -> None:
        self.offsets = np.copy(state)
        self.points = self._base + self.offsets[:, None] * self._normals
        self._last = None

    def refine(self, T_world_cam: np.ndarray, used: np.ndarray, polarity: np.ndarray | None, ex: np.ndarray, ey: np.ndarray,
               et: np.ndarray, ep: np.ndarray, t_us: int, twist: np.ndarray | None, K: np.ndarray,
               prior: tuple[np.ndarray, np.ndarray] | None) -> tuple[np.ndarray, np.ndarray] | None:
        """(pose, covariance) of the events (ideal pixels ``ex``, ``ey``, times ``et`` us, polarities ``ep``) against the
        map points ``used`` (indices) starting from ``T_world_cam`` (the pose at ``t_us``); ``polarity`` (as ``used``)
        the polarity each point may fire (+1 / -1 / 0 both; None = any), ``twist`` the body twist per second (gtsam
        order), ``prior`` = (T_prior, information of the body tangent in squared pixels) or None. None when too few
        events associate or the system is singular."""
        events = (np.array(ex, np.float64), np.array(ey, np.float64), np.array(et, np.int64), np.array(ep, np.int8))
        return self._refine(T_world_cam, used, polarity, events, len(events[0]), t_us, twist, K, prior)

    def _refine(self, T_world_cam, used, polarity, events, n_events, t_us, twist, K, prior):
        """:meth:`refine` of the first ``n_events`` of ``events`` = (ex, ey, et, ep), which it reorders in place."""
        c = self.config
        self._last = None
        fx, fy, cx, cy = float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])
        used = np.ascontiguousarray(used, np.int64)
        m = used.size
        pts, tg = np.empty((m, 3)), np.empty((m, 3))
        pol = _NO_POLARITY if polarity is None else np.ascontiguousarray(polarity, np.int8)
        xi = _NO_TWIST if twist is None or not np.isfinite(twist).all() else np.ascontiguousarray(twist, np.float64)
        T = np.asarray(T_world_cam, np.float64)
        R_cw = np.ascontiguousarray(T[:3, :3].T)
        t_cw = -R_cw @ T[:3, 3]
        ex, ey, et, ep = events
        assoc = np.empty(n_events, np.int64)
        # The associated events first, in order (the others took no part in the sums below).
        n = self.last_events = int(_associate_nearest(self.points, self._tangents, used, R_cw, t_cw, fx, fy, cx, cy,
                                                      float(c.association_radius_px), self._width, self._height, n_events,
                                                      ex, ey, et, ep, pol, pts, tg, assoc))
        if n < int(c.min_events):
            return None
        H, b = np.zeros((6, 6)), np.zeros(6)
        sw, swr = np.empty(m), np.empty(m)
        pose = gtsam.Pose3(T)
        info = None
        if prior is not None:
            T_p, info = gtsam.Pose3(prior[0]), prior[1]
        args = (*self._leads(used, T), float(c.huber_px), float(c.gate_px), H, b, sw, swr)
        n_it = int(c.iterations)
        t_ref = int(t_us)
        for it in range(n_it + 1):
            mat = pose.matrix()
            R_cw = np.ascontiguousarray(mat[:3, :3].T)
            t_cw = -R_cw @ mat[:3, 3]
            _, n_used, swr2 = _linearise_events(n, ex, ey, et, ep, assoc, pts, tg, R_cw, t_cw, fx, fy, cx, cy, xi, t_ref, *args)
            if n_used < int(c.min_events):
                return None
            if it == n_it:
                break  # the last pass measures the covariance and the points' distances at the final pose
            if info is not None:  # H + info, b + info e, the damped solve and its finiteness test in one call
                delta, finite = _lm_step(H, b, info, info @ gtsam.Pose3.Logmap(T_p.between(pose)), True, 0.0)
            else:
                delta, finite = _lm_step(H, b, H, b, False, 0.0)
            if not finite:
                return None
            pose = pose.compose(gtsam.Pose3.Expmap(delta))
        Hf = H + info if info is not None else H
        if not _eigvalsh(0.5 * (Hf + Hf.T))[0] > 0:
            return None
        cov = _inv(Hf) * (swr2 / max(n_used - 6, 1)) * float(c.covariance_scale)
        self._last = (used, sw, swr, R_cw, t_cw, (fx, fy, cx, cy))
        return pose.matrix(), 0.5 * (cov + cov.T)

    def _leads(self, used: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(ON, OFF) lead of each point ``used`` (pixels), the grazing ones (see ``grazing_max_cos``) seen from the
        camera centre of ``T``."""
        c = self.config
        on = np.full(used.size, float(c.on_lead_px))
        off = np.full(used.size, float(c.off_lead_px))
        if self._crease is not None and used.size:
            k = self._crease[used]
            on[k] = float(c.crease_on_lead_px)
            off[k] = float(c.crease_off_lead_px)
            off[~k & (np.einsum("ij,ij->i", self._normals[used], T[:3, 3] - self.points[used]) > 0)] = float(c.beyond_off_lead_px)
        if float(c.grazing_max_cos) > 0 and self._plane_normals is not None and used.size:
            g = grazing_points(self._plane_normals[used], self.points[used], T[:3, 3], float(c.grazing_max_cos))
            on[g] = float(c.grazing_on_lead_px)
            off[g] = float(c.grazing_off_lead_px)
        return on, off

    def learn(self) -> int:
        """Move the points of the last successful :meth:`refine` by ``offset_gain`` of their gauge-free offsets;
        returns how many moved. Call only when the track accepted that update."""
        c = self.config
        if self._last is None or not float(c.offset_gain) > 0:
            return 0
        used, sw, swr, R_cw, t_cw, (fx, fy, cx, cy) = self._last
        self._last = None
        return int(_learn_offsets(used, sw, swr, float(c.offset_min_weight), self.points, self._base, self._normals, self._tangents,
                                  self.offsets, R_cw, t_cw, fx, fy, cx, cy, float(c.offset_gain), float(c.offset_clip_px),
                                  float(c.offset_max_m), 5.0, np.full(6, np.nan)))

    def refine_registration(self, reg, used: np.ndarray, polarity: np.ndarray | None, events, keep: np.ndarray, t_us: int,
                            twist: np.ndarray | None, K: np.ndarray, calibration, predicted: np.ndarray, registration_config) -> bool:
        """Update the successful :class:`~evpose.tracker.registration.RegistrationResult` ``reg`` in place with the step's
        kept events (``events[keep]``), registration's isotropic prior towards ``predicted`` converted into the events'
        units; returns whether it did (else ``reg`` is left as it was)."""
        c = self.config
        self._last = None
        n_all = len(events)
        buffers = (np.empty(n_all), np.empty(n_all), np.empty(n_all, np.int64), np.empty(n_all, np.int8))
        table = calibration.undistortion_table if calibration.dist else _NO_TABLE
        n_kept = int(_kept_events(keep, events.x, events.y, events.t, events.p, table, *buffers))
        if n_kept < int(c.min_events):
            self.last_events = 0
            return False
        prior = None
        rc = registration_config
        s = float(c.prior_residual_px)
        if s > 0 and rc.prior_translation_m > 0 and rc.prior_rotation_deg > 0:
            prior = (predicted, _isotropic_information(float(rc.prior_rotation_deg), float(rc.prior_translation_m), s))
        out = self._refine(reg.T_world_cam, used, polarity, buffers, n_kept, t_us, twist, K, prior)
        if out is None:
            return False
        if c.combine and reg.covariance is not None:
            T_f = gtsam.Pose3(reg.T_world_cam)
            e = gtsam.Pose3.Logmap(T_f.between(gtsam.Pose3(out[0])))
            I_f = inv(reg.covariance)  # a singular one raises as np.linalg.inv
            I_e = _inv(out[1])  # positive definite (checked above), as the sum below
            P = _inv(I_f + I_e)
            reg.T_world_cam = T_f.compose(gtsam.Pose3.Expmap(P @ (I_e @ e))).matrix()
            reg.covariance = 0.5 * (P + P.T)
        else:
            reg.T_world_cam, reg.covariance = out
        return True


def event_registration_for(config, contour_map, tangents: np.ndarray, width: int, height: int) -> EventRegistration:
    """The :class:`EventRegistration` of a :class:`~evpose.tracker.config.TrackerConfig` over ``contour_map`` (its
    painted points and wall feet left out as ``config.event_registration`` says), ``tangents`` its unit edge directions."""
    from evpose.tracker.map_refinement import painted_points
    from evpose.tracker.wall_occlusion import wall_foot_mask

    er, vm = config.event_registration, config.visible_map
    skip = np.zeros(len(contour_map), np.bool_)
    if er.skip_painted:
        skip[painted_points(contour_map, float(config.map_refinement.max_curvature))] = True
    if er.skip_wall_feet:
        skip |= wall_foot_mask(contour_map, vm.wall_inward_m, vm.wall_radius_m, vm.wall_min_height_m, vm.wall_max_height_m)
    return EventRegistration(er, width, height, contour_map.points, tangents, contour_map.edge_normal, skip,
                             contour_map.plane_normal, contour_map.region_id)
