"""Registration settings: the robust loss, how the covariance is scaled, and :class:`RegistrationConfig`.

Kept apart from :mod:`evpose.tracker.registration` (the solver) so the configuration reads in one sitting;
``from evpose.tracker.registration import RegistrationConfig`` keeps working.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field


class RobustLoss(str, enum.Enum):
    """Robust loss ``rho`` on the TDF residual."""

    L2 = "l2"
    HUBER = "huber"
    CAUCHY = "cauchy"
    TUKEY = "tukey"


class ResidualVariance(str, enum.Enum):
    """Which points' residuals give the ``sigma^2`` of the covariance ``(J^T W J)^-1 sigma^2``."""

    INLIERS = "inliers"
    """The weighted squared residuals of the inliers over (inliers - 6).

    Closer to the truth on the bundled demo (registrations from ground truth: std 14-30 mm
    against errors of 2-20 mm; "all": 30-100 mm), but on the simulated landing the
    errors are map biases that persist from update to update, and a filter that
    believes the registrations more follows them: ``stpe`` 97.8 / 80.3 mm against
    70.7 / 84.0 mm at 346x260 / 240x180 (world-frame velocity, no registration prior)."""
    ALL = "all"
    """Those of every point inside the image over (inliers - 6), as before: the 60-80 % of points whose edge
    did not fire (TDF ~1, no gradient, no curvature) add ~w each: the reported standard deviations about double."""


@dataclass
class RegistrationConfig:
    """Registration settings."""

    max_points: int = field(default=1000, metadata={"min": 50, "max": 20000, "step": 50, "unit": "points"})
    """Visible points used per step; more are subsampled with a fixed stride (deterministic), points.

    Accuracy on the simulated landing is limited by biases, not by the number of
    points: ``stpe`` ATE 54 / 56 / 57 mm with 800 / 1500 / 3000 points at 346x260
    (83 / 74 / 70 mm at 240x180), so 1000 keeps registration time down. Session 9 (seeds 0-3, 13.42 / 19.00 mm):
    1500 / 2000 gave 13.05 / 19.15, 13.64 / 19.52 mm. The per-update error is shared by whole edges: on the true-edge
    map at the truth (240x180, seed 0) the TDF minimum's offset from the edge, averaged per edge and update, spreads
    by 0.22 px about the edge's mean (0.08 px if its points were independent), correlated 0.86 over 5 ms, 0.72 over
    100 ms, 0.30 over 200 ms, unexplained by normal speed, polarity, distance from the image centre or depth; it is
    not the sub-pixel phase of the edge either (mean offset flat over the phase): more points do not average it. Session 9, ``full``, seeds 0-3, 346x260 /
    240x180: 600 points 8.21 / 9.78 mm against 7.78 / 9.40 (~0.5 ms less CPU per update, unpaired); registering no
    buffer-zone point (no geometric polarity; ~30 % of the used points) 9.40 (without their ``T_align`` patches) /
    9.11 mm (with them) at 346x260: the points are what ``full``'s accuracy rests on, not kept. Session 13, ``full``
    with the event registration, seeds 0-3 / 4-7: 700 / 800 points 6.69 / 6.07 and 6.60 / 5.94 mm at 346x260, 7.43 /
    9.11 and 7.49 / 8.89 mm at 240x180, against 6.38 / 5.91 and 7.25 / 8.49 mm with 1000 (~0.3-0.5 ms less CPU per
    update at 700, unpaired): not changed. Session 29, ``full`` at 240x180 seeds 0-7 (6.955 mm; ``/tmp/s29/reg29/``):
    1500 gave 6.918 mm (ARE 0.0772 -> 0.0817 deg). Session 41 (lat41, ``/tmp/s41/lat41/``), 700 against 1000: CPU per
    update of ``full`` at 346x260 (seed 0, the two configurations stepped alternately in one process, ``pairstep.py``,
    load ~18) -0.277 +- 0.031 ms of 4.39 (-6 %); ATE at 240x180 2 s seeds 0-12 4.614 -> 4.693 mm (+0.078 +- 0.106, 3
    of 13 better; ``acc/run.sh``, ``acc/cmp.py``), 346x260 seed 0 3.647 -> 3.729 mm; and with fewer points the map
    acquisition's chance z-score falls below ``map_acquisition.min_chance_z`` (15.6-15.8 against 16) on 3 of those 13
    right maps, which ``evpose track`` then refuses (run with ``--acquire-s 0``): not changed."""

    second_order: bool = True
    """Newton steps using the TDF's curvature (points on the TDF minimum still constrain the pose) instead of Gauss-Newton.

    Gauss-Newton converges poorly from a few cm / degrees away (flat TDF regions), so
    it stays nearer its start: on the simulated landing that acts as a regulariser
    of the weakly observed tilt-vs-sideways direction, not as a better minimum (session 9, ``stpe`` seeds 0-3:
    78.6 / 87.8 mm without it).

    Session 15, ``full`` seeds 0-3 at 346x260 / 240x180 (6.38 / 7.25 mm; the field echoes the prediction in tilt and
    height, see :mod:`evpose.tracker.event_registration`): Gauss-Newton steps and covariance 5.83 / 9.17 mm;
    Gauss-Newton steps with the second-order covariance 6.43 / 8.88; second-order steps with the first-order
    covariance 6.27 / 9.27, or with its shape scaled to the second-order determinant 6.44 / 7.90 mm. The 346x260 gain
    is the larger covariance (as the field's covariance scaled 10x before combining), not the steps.
    Session 16: the second-order covariance is not over-confident at the scale that matters (the cost's rise at +-3
    claimed standard deviations is 0.2-0.9 of the claim in the weak directions); capping the information by that
    rise helps 346x260 and costs 240x180 (see :mod:`evpose.tracker.event_registration`).

    Session 9, not kept: the gradient and curvature projected on each point's projected edge normal (along the edge
    the field only shows its events' scatter): ``stpe`` seeds 0-3 13.42 / 19.00 -> 14.00 / 18.34 mm at 346x260 /
    240x180; with ``visible_map.wall_occlusion`` 11.92 / 18.26 -> 13.00 / 16.81 (seeds 0-3) and 11.63 / 19.86 ->
    12.38 / 17.77 mm (seeds 4-7): better at 240x180 only. Session 10: on for coarse sensors only, see
    ``normal_gradient_min_pixel_mrad``."""
    normal_gradient_min_pixel_mrad: float = field(default=5.0, metadata={"min": 0.0, "max": 100.0, "step": 0.1, "unit": "mrad"})
    """In ``stpe`` and ``stpe+filter``: when one pixel subtends at least this angle (``1 / fx``), the field's gradient
    and curvature are taken along each point's projected edge normal alone (points whose map edge direction is
    unknown keep both), milliradians (0 = never). The fused modes never do.

    Along the edge the field shows only its events' scatter, not the edge's position; on a coarse sensor that
    scatter is a larger share of the gradient (session 9, see ``second_order``: better at 240x180, worse at
    346x260). The simulated landing's 70 deg cameras: 4.05 mrad at 346x260 (off), 5.83 mrad at 240x180 (on).
    Session 10, 2 s landing from the truth, 240x180, ATE / ARE mean, off -> on: ``stpe`` seeds 0-3 18.47 / 0.238 ->
    16.80 mm / 0.250 deg (17.38 18.63 20.75 17.12 -> 18.64 14.23 17.25 17.08 mm), seeds 4-7 20.12 / 0.229 -> 17.95 /
    0.236; ``stpe+filter`` seeds 0-3 21.70 -> 18.71 mm (ARE 0.295 deg); 346x260 and ``full`` bit-identical.
    Combined with it at 240x180 (``stpe`` seeds 0-3, 16.80 mm), not kept: ``robust_scale`` 0.45 16.50, ``rate_hz``
    300 16.83, ``max_points`` 1500 16.73, ``time_surface.eta_ms`` 14.4 with ``field_lag_ms`` 5.2 (both scaled by
    the pixel pitch) 18.15, ``visible_map.crowded_radius_px`` 2 17.89, ``motion_filter.measurement_covariance_scale``
    2 17.94 mm."""
    max_iterations: int = field(default=10, metadata={"min": 1, "max": 100, "step": 1, "unit": "iterations"})
    """Levenberg-Marquardt iterations per step, at most. (Session 9, ``full`` seeds 0-3: 1 instead of the median 2
    gave 8.35 / 9.36 mm against 7.77 / 9.40 at 346x260 / 240x180, 0.1-0.15 ms less registration CPU: not kept.
    Session 13, ``full`` with the event registration after it, mean ATE of seeds 0-3 / 4-7: 1 gave 6.43 / 5.86 mm at
    346x260 and 7.40 / 8.97 at 240x180, 2 gave 6.38 / 5.89 and 7.49 / 8.56, against 6.38 / 5.91 and 7.25 / 8.49 mm
    (mean iterations per update 2.4 / 2.7 -> 1.6 with 2): not kept. Session 42 (lat42, ``/tmp/s42/lat42/``), as a
    speed lever: CPU per update of ``full`` at 346x260 (seed 0, both configurations stepped alternately in one process,
    ``pairstep.py``, load ~13) 2: -0.167 +- 0.019 ms mean (-0.12 median, ~4 %), 1: -0.226 +- 0.056; ATE with 2 (CLI,
    240x180 2 s, paired against main's defaults, ``acc/run.sh``, ``acc/cmp.py``): nominal seeds 0-23 4.770 -> 4.795 mm
    (+0.026 +- 0.040, 11 of 24 better), flights 1-12 14.187 -> 14.153 (-0.034 +- 0.149, 6 of 12), flights 13-24
    14.906 -> 15.138 (+0.232 +- 0.098, 2 of 12): not kept.)"""
    robust_loss: RobustLoss = RobustLoss.HUBER
    """Robust loss on the residual."""
    robust_scale: float = field(default=0.3, metadata={"min": 0.01, "max": 2.0, "step": 0.01, "unit": "TDF"})
    """Scale of the robust loss, in TDF units (the TDF runs from 0 on an edge to 1 far from events).

    Session 9, ``stpe`` seeds 0-3 (346x260 / 240x180, 13.42 / 19.00 mm at 0.3): 0.2 / 0.4 / 0.45 / 0.5 / 0.6 gave
    13.55 / 19.66, 13.41 / 18.49, 13.31 / 18.42, 13.23 / 18.57, 13.45 / 19.60 mm; Cauchy 0.3 / 0.5 14.81 / 19.50,
    13.84 / 18.40; 0.45 with the wall-foot occlusion, seeds 4-7: 11.79 / 19.59 against 11.63 / 19.86 mm. Within
    the runs' chaotic spread (about +-1 mm per seed), and ``full`` shares it: not changed.

    Session 29, ``full`` at 240x180 (``/tmp/s29/reg29/run.py``; 2 s landing from ground truth, seeds 0-7, 6.955 mm):
    0.45 / 0.2 gave 6.964 / 6.845 mm; 0.2 with the events' thresholds kept in angle
    (``event_registration.angle_reference_pixel_mrad`` at ``angle_pixel_exponent`` 1, 6.727 mm) 6.614 mm, held-out
    seeds 8-11 6.508 -> 6.408-6.446 mm (two runs a rounding apart), 3 s landing seeds 0-3 18.132 -> 17.985 mm: a tenth
    of a millimetre, the size of the runs' chaotic spread of an 8-seed mean (0.03-0.1 mm between runs a rounding
    apart); not tried with the default exponent 2: not changed."""
    inlier_threshold: float = field(default=0.7, metadata={"min": 0.05, "max": 1.0, "step": 0.01, "unit": "TDF"})
    """A point is an inlier if its final TDF value is below this, TDF units."""
    lm_lambda: float = field(default=0.01, metadata={"min": 0.0, "max": 10.0, "step": 1e-4, "unit": "ratio"})
    """Initial Levenberg-Marquardt damping, relative to the Hessian diagonal."""
    lm_lambda_min: float = field(default=0.001, metadata={"min": 0.0, "max": 10.0, "step": 1e-3, "unit": "ratio"})
    """Smallest damping: the TDF minimum is not zero, so undamped Gauss-Newton steps overshoot, relative."""
    convergence_rotation_rad: float = field(default=1e-5, metadata={"min": 1e-8, "max": 1e-2, "step": 1e-6, "unit": "rad"})
    """Stop when an accepted step rotates less than this, radians (and translates less than below)."""
    convergence_translation_m: float = field(default=1e-5, metadata={"min": 1e-8, "max": 1e-2, "step": 1e-6, "unit": "m"})
    """Stop when an accepted step translates less than this, metres."""
    convergence_cost_ratio: float = field(default=1e-3, metadata={"min": 0.0, "max": 0.1, "step": 1e-5, "unit": "ratio"})
    """Also stop when an accepted step lowers the mean cost by less than this fraction.

    On the simulated landing (2 s, built map) 1e-3 instead of 1e-4 halves the
    iterations (median 5 -> 2) and registration CPU, with ATE unchanged within run
    to run noise in ``stpe`` (56 / 74 -> 54 / 80 mm at 346x260 / 240x180) and
    ``full`` (31.5 / 38.4 -> 30.7 / 38.6 mm, same-window runs).

    0 leaves only the step-size test above. Tried with thresholds of 0.1 / 0.5 / 2 mm
    and 0.006 / 0.03 / 0.11 deg (built map, 2 s): with Tukey (scale 0.7) ``stpe`` lost
    119-350 of 393 updates at 346x260 or 240x180 (ATE 0.1-0.8 m) and ``full`` got
    35-81 mm against Huber's 19.5 / 22.9 mm; with Huber, ``stpe`` ATE 115-129 / 89-100
    mm against 140 / 108 mm for this test but ``full`` 19.5-20.3 / 23.8-25.3 mm and
    up to 10 iterations per update, so the cost test stays the default. Session 8, ``full`` seeds 0-3 (buffer-zone
    trail 0), 0 with 30 iterations: 8.65 / 9.85 mm against 9.15 / 9.51 at 346x260 / 240x180, median iterations
    2 -> 12. Session 15, ``full`` 346x260 seeds 0-3 (6.38 mm): 1e-4 / 0 gave 6.33 / 6.52 mm; converged or not, the
    field stays where it starts in tilt and height (see :mod:`evpose.tracker.event_registration`)."""
    prior_translation_m: float = field(default=0.01, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "m"})
    """Std of a Gaussian prior pulling the pose towards the prediction, translation, metres (0 = no prior).

    Directions the visible map barely constrains (tilt vs. sideways shift over flat
    ground) then follow the motion model instead of drifting with small biases.
    Too tight a prior makes the track follow the constant-velocity model: on the
    simulated landing (lag compensated, 346x260 / 240x180) 1 mm / 0.02 deg gave
    83 / 89 mm ATE, 2 mm / 0.05 deg 35 / 54 mm, 5 mm / 0.1 deg 18 / 31 mm,
    10 mm / 0.2 deg 18 / 26 mm, none 105 / 28 mm. Session 8, ``full`` (buffer-zone trail 0), seeds 0 / 1 at 346x260
    (11.37 / 8.23 mm with this prior): none 9.70 / 8.56 mm; the prior kept but the reported covariance the events'
    alone (the fusion counts the prediction once) 10.23 / 8.29; that and the pose moved to the events' own minimum
    (one Newton step, ``H_e^-1 P e``) 11.04 / 8.61, with converged registrations (seeds 0-3) 9.02 / 9.78 mm against
    9.15 / 9.51 at 346x260 / 240x180."""
    prior_rotation_deg: float = field(default=0.2, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "deg"})
    """Std of the same prior, rotation, degrees (0 = no prior). Session 9, ``full`` seeds 0-3 (7.78 / 9.40 mm at 0.2):
    0.1 / 0.05 gave 7.82 / 9.57, 7.42 / 10.28 mm. Session 15, ``full`` 346x260 seeds 0-3 (6.38 mm): no prior
    (``prior_translation_m`` 0, field and events) 6.95 mm; the priors kept but their information left out of the
    reported covariances 6.43 mm; session 18, the same at 240x180 seeds 0-7 (both priors' information subtracted
    from the field's and the events' Hessians, eigenvalues floored at 1e-6 of the largest) 7.44 mm against 7.325."""
    fused_prior_reference_pixel_mrad: float = field(default=4.05, metadata={"min": 0.0, "max": 100.0, "step": 0.01, "unit": "mrad"})
    """In the fused modes, on a sensor whose pixel subtends more than this angle (``1 / fx``), both stds of the prior
    towards the prediction (``prior_rotation_deg``, ``prior_translation_m``; the field's and the events') grow by
    ``(pixel / this) ** fused_prior_pixel_exponent``, milliradians (0 = never). The stds were tuned on the simulated
    346x260 70 deg camera (4.05 mrad: unchanged, as the bundled demos); its 240x180 sibling has 5.83 mrad.

    The data's information per point falls with the pixel (the image Jacobian goes as ``fx``, squared in the normal
    equations) and a coarser sensor fires fewer events, while the prior stays as strong in pose units: at 240x180 the
    prior holds a larger share of the registration, which keeps about twice as much of the prediction's error as at
    346x260 (the echo measured in :mod:`evpose.tracker.event_registration`, session 20).

    Session 20, ``full`` from ground truth, mean ATE mm / ARE deg at 240x180 (``/tmp/s20/res7/run.py``, ``run3.py``),
    off -> on (exponent 2, stds x 2.08): 2 s landing seeds 0-7 7.325 / 0.0802 -> 7.007 / 0.0771 (per seed 10.65 4.85
    9.60 4.07 11.71 4.87 6.56 6.30 -> 10.35 4.87 8.89 4.17 10.13 5.32 6.10 6.23), held-out seeds 8-11 6.855 / 0.0744
    -> 6.807 / 0.0796 (5.79 6.62 2.79 12.22 -> 6.30 6.78 3.51 10.64), 3 s landing seeds 0-3 18.91 / 0.162 -> 18.64 /
    0.186 mm (23.41 18.50 13.80 19.93 -> 20.56 16.59 15.76 21.64; ~150 updates lost in every run either way). A
    modest gain, on the seeds with large errors; 346x260 and the demos are bit-identical. Exponent 3 (x 2.99) 7.008 /
    0.0776 (seeds 0-7); the stds scaled by hand x 1.44 / x 2 7.134 / 0.0775, 6.964 / 0.0762. The echo with it on
    (same probe, seeds 0 and 4): diagonal 0.50 / 0.27 / 0.26, 0.46 / 0.58 / 0.35 -> 0.48 / 0.22 / 0.22, 0.34 / 0.39 /
    0.34; the rest is not the prior's. The EKF backend, seeds 0-7: 7.371 / 0.0788 -> 7.125 / 0.0783 (the graph 7.007)."""
    fused_prior_pixel_exponent: float = field(default=2.0, metadata={"min": 0.0, "max": 4.0, "step": 0.1, "unit": "ratio"})
    """Power of the pixel-angle ratio the prior's stds grow by (``fused_prior_reference_pixel_mrad``); 2 follows the
    events' information (Jacobian squared times the event count, each ~``fx^2``), 1 the field's (its points capped
    at ``max_points``), ratio."""
    prior_residual_sigma: float = field(default=0.2, metadata={"min": 0.01, "max": 1.0, "step": 0.01, "unit": "TDF"})
    """Typical TDF residual of one point, which converts the prior stds into the cost's units, TDF units."""
    residual_variance: ResidualVariance = ResidualVariance.ALL
    """Residuals that set the covariance's scale (see :class:`ResidualVariance`). Session 29, ``full`` at 240x180 (the
    field then weighs ~2x more against the events and the IMU; seeds 0-7, ``/tmp/s29/reg29/``): ``inliers`` 6.955 ->
    7.596 mm."""
    min_points: int = field(default=30, metadata={"min": 6, "max": 1000, "step": 1, "unit": "points"})
    """Fewer points projecting into the image than this means the track is lost, points."""
    min_inlier_ratio: float = field(default=0.1, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Fewer inliers than this share of the points used means the track is lost.

    Contours parallel to the image motion fire no events, so even at the true pose
    only 12-20 % of the visible points of the simulated landing read TDF < 0.7;
    0.15 declared 5-25 % of its (accurate) updates lost. On the bundled 4 s demo
    (``demo_data/landing.h5``, 7.8 m up) registrations started at ground truth
    land within 20 mm / 0.2 deg of it at 0.2-0.3 s with only 56-69 inliers of 810
    points (7-8 %), and 0.1 declares them lost (``stpe`` loses the track at
    0.22 s). 0.05 keeps ``stpe`` on it until 1.96 s (0.07: 0.25 s; 0.03: 1.99 s),
    but after that it reports 50-160 "OK" poses 5-7 m off (a wrong lock with
    > 5 % inliers): a confidently wrong track is worse than a lost one, so 0.1
    stays. ``full`` at 240x180 (pinned map): 20.0 mm, 0 lost with 0.05 against
    20.1 mm, 3 lost. The fused modes use ``fused_min_inlier_ratio`` instead."""
    weak_inlier_ratio: float = field(default=0.04, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """``stpe`` with the Kalman motion model: a registration with fewer inliers than ``min_inlier_ratio`` but at
    least this share is weak, not a lost track: it is fused when it agrees with the motion prediction
    (``motion_filter.weak_gate_sigma``), else the track is lost (0 = off: every such registration loses it), ratio.

    Only a track never lost since its start takes weak registrations; a lost one stays lost unless
    ``regain_updates`` strict registrations in a row pick it up.
    Measured on the bundled 4 s demo (``evpose track demo_data/landing.h5 --map maps/landing_map.ply --mode stpe``,
    ``evpose eval --align none``), 0 -> 0.04: first loss 0.25 -> 2.03 s, lost updates 489 -> 394 of 793,
    ATE of the written poses RMSE 800 -> 125 mm, max 6963 -> 240 mm (the strict test alone had let a
    coasted prediction 5.7 m off pass once, then kept it); 0.03 and 0.05 alike (max 241 mm). The
    simulated landing never fails the strict test (``stpe`` and ``full`` bit-identical, seeds 0-3)."""
    weak_run_degraded_updates: int = field(default=10, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """With the weak-registration test (``weak_inlier_ratio``): from this many updates in a row held only by weak
    registrations on, they are reported degraded instead of OK, poses and learning unchanged (0 = never), updates.

    A weak registration is fused when it agrees with the motion model, so a long run of them follows the model's drift
    while reporting OK. Session 15, ``stpe``, RMS / max error of the updates left OK and RMS of those this degrades
    (``/tmp/s15/lead/weak.py``): 3 s landing seed 0 (372 OK, 121 mm RMS, 382 max) at 5 / 10 / 20 / 40: 86 / 69 / 43 /
    10 degraded, the rest 68 / 74 / 89 / 117 mm (max 217 / 233 / 291 / 382), the degraded 219 / 235 / 258 / 223 mm;
    seed 1 (353 OK, 105 mm) 55 / 44 / 27 / 7 degraded, the rest 69 / 76 / 88 / 101 mm; the demo landing (396 OK, 141
    mm) 62 / 33 / 15 / 0, the rest 133 / 135 / 137 / 141 mm, the degraded 179 / 198 / 219 mm. The 2 s landings
    (seeds 0 / 1) never register weakly. At 10 the rest still reaches 233-311 mm: wrong locks also pass the strict test
    between weak runs."""
    regain_updates: int = field(default=0, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """With the weak-registration test (``weak_inlier_ratio``): a lost track is held again after this many
    registrations in a row pass the strict test, the updates before that reported lost (0 = never), updates.

    The strict test cannot tell a wrong lock on a coasted prediction from a right one: on the indoor demo
    (``evpose track demo_data/indoor.h5 --map maps/indoor_map.ply --mode stpe``, lost at 0.64 s) wrong
    locks 0.35-4.5 m off passed it more than 20 times in a row. Poses written (ATE RMSE / max): 5 -> 361
    (2158 / 4505 mm), 20 -> 318 (2233 / 4505 mm), never -> 121 (97 / 170 mm; before the weak test, which
    reported every strict pass: 117, 192 / 856 mm). The landing demo never regains a right lock either."""
    fused_min_inlier_ratio: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """``min_inlier_ratio`` where an IMU fusion backend drives the pose (``full``), ratio.

    There a registration that fails the test is not a lost track but a gap the IMU
    bridges, and a weak registration that passes is still weighed by the fusion
    (its covariance, the robust factor), so a wrong lock cannot run away as in
    ``stpe``. Measured 0.1 -> 0.05, ``full``, bundled landing map (online ATE / ARE,
    degraded updates): demo ``landing`` 19.9 -> 17.4 mm, 0.200 -> 0.218 deg, 255 -> 50
    of 793; ``landing_dynamic`` 47.3 -> 34.9 mm, 0.353 -> 0.322 deg, 175 -> 65 of 593;
    the same 3 s flight without moving objects 49.9 -> 34.5 mm; ``landing_fast`` and the
    2 s landing benchmark (no failed test) unchanged. 0.07: 17.0 / 37.4 / 36.5 mm;
    0.03: 17.4 / 34.2 / 33.2 mm. A wrong map passes the loose test now and then (the
    landing demo against the indoor map: 75 of 793 updates at 0.05, a trajectory 0.5 m
    off), so it applies only once the map is acquired: ``ACQUIRE_UPDATES``
    (``evpose.tracker.tracker``) registrations in a row passing ``min_inlier_ratio``,
    which the wrong map never does (``evpose track`` then refuses it).

    Session 15, the 3 s landings (``full``, seeds 0-3, 346x260, 232 degraded updates, nearly all in the turn at
    1.4-2 s, where 3-7 % of the points lie on recent events even at the truth): 0.03 / 0.02 gave ATE 15.72 ->
    15.71 / 15.69 mm (ARE 0.163 -> 0.161 / 0.162 deg, 6 / 0 degraded): those registrations are as good as the IMU
    bridge (seed 0: 10-20 mm from the IMU-predicted start), neither better nor worse. Not changed."""
    max_condition: float = field(default=1e8, metadata={"min": 1e3, "max": 1e14, "step": 1e3, "unit": "ratio"})
    """Largest acceptable condition number of the (scaled) Hessian; above it the geometry is degenerate."""
    field_lag_ms: float = field(default=4.5, metadata={"min": 0.0, "max": 50.0, "step": 0.1, "unit": "ms"})
    """How far the TDF's minimum trails the edges it shows, milliseconds; used when a motion twist is given.

    The newest events of a moving edge sit on the pixels it crossed last, and the
    time-surface trail behind them pulls the (blurred) minimum further back, so the
    field shows the map as seen ``field_lag_ms`` before the query time (measured
    4-5 ms with ``eta`` 10 ms and a 5 px blur on the simulated landing). The pose is
    registered at that time and moved forward by the motion twist.

    Re-measured per point (``registration_bias_346x260``, ``true_edges_offset_*``: the TDF minimum's offset from
    the true edge along its image normal, at the truth, 3 px blur): ``-0.09 px - 4.1 ms x normal speed``, so this
    lag is right on average and a constant pixel term would add < 0.1 px. What is left is spread, not bias:
    0.60 px per point and 0.25 px between the edges' means (OFF edges trail ON edges by ~0.2 px on the pad
    marker: a pixel's last event fires later in a bright-to-dark crossing of its footprint, log response).
    Session 7, ``stpe`` seeds 0-3, mean ATE at 240x180: 3.5 / 4.5 / 5.5 ms gave 24.26 / 23.80 / 23.31 mm (no change
    worth a per-resolution lag; ``time_surface.eta_ms`` 15 with 5.5 ms and crowding at 2.08 px: 16.61 / 22.01 mm at
    346x260 / 240x180, against 15.82 / 22.21). Registering the level set
    ``TDF = 1 - exp(-lag / eta)`` (signed residual, the edge's position ``lag`` ago, sub-pixel on the ramp) instead of
    the minimum lost badly: lag 6 / 8 ms 27.2 / 27.0 mm at 346x260, 8 ms 39.4 mm at 240x180.
    Registrations from the truth with the points moved by a per-polarity fit (converged, 346x260) were no
    better than the global fit once one outlier was set aside; a per-segment oracle offset only 11.6 -> 9.1 mm.
    Session 8, ``full``, a trail affine in the normal speed (floor off, every point 0.5 px + 2.5 ms x speed, or
    0.7 px + 1.5 ms): seeds 0 / 1 14.5 / 9.8 and 24.8 / 12.7 mm at 346x260 against 11.4 / 8.2.
    Session 9, ``full`` seeds 0-3 (7.78 / 9.40 mm): 4.0 / 5.0 ms 7.82 / 10.76, 8.31 / 9.19 mm; 240x180 alone 5.5 / 6.5
    ms 10.04 / 12.31 mm. The registrations' image-shift error against the true camera velocity: a lag-like term
    explains only ~20 % of its variance (the cross-flow part -6 ms x velocity at 346x260, ~0 at 240x180).
    Session 14, ``full``, the 3 s landings of ``fused_lag_floor_px`` (seeds 1 / 2 / 3, 18.38 / 16.33 / 15.28 mm): 3 / 6 ms
    gave 20.19 / 17.81 / 17.90, 18.32 / 17.59 / 15.80 mm.
    Session 15 (``full``, registrations from the truth with the true twist, no prior, true-edge map, refiner off,
    seeds 0 / 2 at 346x260): the pose is registered ``field_lag_ms`` back and moved forward by the twist, so a lag
    change moves the roll by the yaw rate times the change, no more (3 -> 6 ms: -20 / +18 / +23 / -10 / -27 mdeg per
    ms at 0.2 / 0.6 / 1.0 / 1.4 / 1.8 s, yaw rate -20 / +21 / +23 / -16 / -26 deg/s). 4.5 ms gives the smallest
    roll spread (27.7 / 25.0 mdeg against 38.6 / 37.8 at 3 ms and 49.1 / 43.6 at 6 ms); what is left is a slow offset
    (mean -20 / -11 mdeg, -56 / -32 mdeg in the last 0.2 s) that does not follow the yaw rate (correlation +0.16 /
    +0.12; with the lateral image flow -0.39 / -0.18, the number of points -0.18 / -0.27), and the roll drift
    costs ``full`` nothing (see :mod:`evpose.tracker.event_registration`)."""
    lag_floor_px: float = field(default=0.0, metadata={"min": 0.0, "max": 3.0, "step": 0.05, "unit": "px"})
    """Smallest distance the TDF minimum trails a moving edge, pixels (0 = off); needs the map's edge directions
    and the motion twist. The fused modes use ``fused_lag_floor_px`` instead.

    ``field_lag_ms`` makes the trail proportional to the edge's normal image speed, but slow edges trail by a
    nearly constant amount (``registration_bias_346x260``, true-edge map: -0.52 / -0.46 / -0.52 px at 0.03 /
    0.08 / 0.13 px/ms against -0.15 / -0.36 / -0.56 px for 4.5 ms): each point's field is then sampled behind
    its projection by the difference, along its projected edge normal, against the direction of its image
    motion. Registrations from the truth (true twist, true-edge map, 346x260): 11.9 -> 10.0 mm RMS with 0.55 px
    (7.4 -> 5.4 mm with ``crowded_radius_px`` 3). But ``stpe`` tracks worse with it (seeds 0-3, 2 s landing,
    346x260 / 240x180, crowded points skipped: 21.79 / 28.49 -> 21.99 / 29.92 mm with 0.3 px, 23.8 / 36.1 mm with
    0.55 px at 2.5 px crowding): the Kalman filter's twist gets the motion direction of slow points wrong. Session 7
    (rebuilt maps, crowding 2.08 px at 240x180): 0 / 0.3 / 0.45 px 15.82 / 22.21, 16.01 / 23.04, 17.09 / 26.51 mm.
    Session 11, ``stpe`` at 240x180 with the normal-only gradients (seeds 0-3, 16.80 mm): a constant trail on every
    point (no floor) of +0.1 / +0.2 / -0.1 px gave 19.94 / 26.81 / 18.70 mm (with ``field_lag_ms`` 5.5: 19.30 / 26.18
    at +0.1 / +0.2), though at the truth the field's minimum sits 0.09 px further behind than the lag model says.
    A trail growing with the distance from the image centre (the from-truth offsets trail 0.28-0.35 px x r^2 more
    at the border, r = distance / focal length, both resolutions), ``0.3 (r^2 - 0.25)`` px: 16.30 / 22.96 mm."""
    fused_lag_floor_px: float = field(default=0.45, metadata={"min": 0.0, "max": 3.0, "step": 0.05, "unit": "px"})
    """``lag_floor_px`` where an IMU fusion backend drives the pose (``full``): its twist comes from the IMU, pixels.

    ``full``, 2 s landing from ground truth, seeds 0-3, mean ATE at 346x260 / 240x180 (``crowded_radius_px`` 3,
    ``fused_polarity_trail_px`` 0): 0 -> 0.45 px 11.72 / 12.33 -> 10.37 / 10.56 mm (ARE 0.125 / 0.151 -> 0.131 / 0.155 deg); sweep (with the
    earlier crowding variant) 0 / 0.3 / 0.45 / 0.55 / 0.65 px 11.74 / 12.39, 11.05 / 11.16, 10.39 / 10.50,
    9.88 / 12.43, 10.99 / 15.63 mm. Bundled demos, ``full``, ``--align none``, 0 -> 0.45 px: ``landing`` 15.28 ->
    15.79 mm, ``landing_dynamic`` 24.83 -> 21.83 mm, ``landing_fast`` 23.57 -> 24.19 mm (ARE 0.227 -> 0.231 deg).

    Session 14 (with the event registration), the optimum is not the same on other flights. 3 s landings
    (``evpose simulate --scenario landing --seconds 3 --seed S``, 346x260, map by ``evpose build-map`` from its cloud,
    ``evpose track`` / ``evpose eval --align none``, ATE RMSE, seeds 1 / 2 / 3): 0.45 18.38 / 16.33 / 15.28 mm, 0.3
    19.19 / 17.26 / 15.88, 0.6 15.85 / 14.40 / 14.22, 0.8 13.86 / 11.79 / 13.66 (ARE 0.183 / 0.201 / 0.126 -> 0.159 /
    0.185 / 0.105 deg), 1.1 12.94 / 10.82 mm (ARE 0.194 / 0.217); the bundled demos at 0.8: ``landing`` 9.71 ->
    10.60, ``landing_fast`` 18.20 -> 19.83, ``landing_dynamic`` 12.27 -> 7.11 mm; the 2 s benchmark at 0.6 (seeds
    0-3) 6.38 -> 6.72 mm at 346x260, 7.25 -> 8.95 at 240x180; the same 3 s landings at 240x180 (their own maps) 18.79
    / 16.02 / 21.76 -> 22.41 / 18.54 / 26.85 mm at 0.8. The floor moves the horizontal (tilt-vs-shift) error
    of the 3 s flights (second 1-2, seed 2: 22.0 -> 14.1 mm RMS at 0.8); their height error in that second (12-15
    mm RMS, the fused estimate too high by up to 21 mm while the registrations read 6-16 mm) stays with every floor:
    a trail constant in pixels is a stand-in for something that differs between these flights. Not changed."""
    fused_polarity_trail_px: float = field(default=0.2, metadata={"min": -1.0, "max": 1.0, "step": 0.05, "unit": "px"})
    """In the fused modes, how much further the field of a point predicted to fire OFF events trails than that of an
    ON point (the polarity filter's prediction), pixels: each is sampled half of it behind / ahead of the lag model,
    along its edge normal (0 = off).

    A pixel's last event of a crossing fires later in a bright-to-dark (OFF) crossing of its footprint than in a
    dark-to-bright one (log response): on the simulated landing's true-edge map OFF segments trail ~0.2 px more
    (``registration_bias``; registrations from the truth, oracle offsets: 5.6 -> 5.1 mm with 0.1 px, 7.8 mm with
    -0.2 px). ``full``, seeds 0-3, mean ATE at 346x260 / 240x180 (with ``fused_lag_floor_px`` 0.45): 0 / 0.1 / 0.2 /
    0.3 / -0.2 px gave 10.37 / 10.56, 10.05 / 10.21, 9.83 / 10.06, 10.05 / 10.12, 10.37 / 11.42 mm (ARE 0.131 /
    0.155 -> 0.123 / 0.152 deg at 0.2). Bundled demos (``full``, ``--align none``) 0 -> 0.2: ``landing`` 15.79 ->
    15.55 mm, ``landing_dynamic`` 21.83 -> 20.58 mm, ``landing_fast`` 24.19 -> 23.88 mm. ``stpe+filter`` (not
    applied there) would go 22.28 / 30.38 -> 22.47 / 28.54 mm."""
    fused_grazing_off_trail_px: float = field(default=0.2, metadata={"min": -1.0, "max": 1.0, "step": 0.05, "unit": "px"})
    """In the fused modes, how much further the field of a point predicted to fire OFF events trails when its surface
    is seen at a grazing angle (``event_registration.grazing_max_cos``; 0 there turns this off too), along its edge
    normal, pixels (0 = off): the OFF events of such points sit ~0.15 px further behind their edges than the face-on
    points' (see ``EventRegistrationConfig.grazing_max_cos``, which also gives the figures: 0 / 0.1 / 0.2 / 0.3 px
    with the events' grazing leads 6.76 / 6.67 / 6.57 / 6.49 mm averaged over the four 2 s sets, 0.3 trading
    240x180 seeds 0-3 for the rest, 7.58 mm against 7.25 off)."""
    fused_crease_off_trail_px: float = field(default=0.0, metadata={"min": -1.0, "max": 1.0, "step": 0.05, "unit": "px"})
    """In the fused modes, how much further the field of a face-on point predicted to fire OFF events trails on a
    crease (``event_registration.crease_radius_m``; 0 there turns this off too) than elsewhere, pixels: each is
    sampled half of it behind / ahead, along its edge normal (0 = off).

    With the events' measured crease split (``EventRegistrationConfig.crease_radius_m``; crease -0.26 / other -0.05
    px, no ``beyond_off_lead_px``: 5.84 / 5.14 / 7.69 / 7.57 mm, the four 2 s sets), 0.2 / -0.1 px gave 6.32 / 5.31 /
    7.99 / 7.34 (6.74) and 6.01 / 5.19 / 7.77 / 7.73 mm (6.67) against 6.56: not kept."""
    fused_buffer_trail_px: float = field(default=0.1, metadata={"min": -1.0, "max": 1.0, "step": 0.05, "unit": "px"})
    """In the fused modes, how much further behind the lag model the field of a point in the polarity filter's buffer
    zone (predicted polarity 0: its patch shows events of both polarities) is sampled, along its edge normal, pixels
    (0 = as the model says).

    ``full`` with its prediction replaced by the truth (seeds 0 and 1, 2 s landing), the TDF minimum of every
    registered point against the trail model (lag, floor, polarity split), by normal speed 0.05-0.1 / 0.15-0.2 /
    0.2-0.25 px/ms: ON and OFF points within ~0.1 px of it (OFF up to 0.17 px ahead at 240x180), buffer-zone points
    (about half of those registered) -0.13 / -0.09 / -0.26 px at 346x260 and +0.04 / -0.16 / -0.27 px at 240x180:
    behind it. Their shared offset moves the whole image (0.1-0.3 px), which the fusion, unable to tell a tilt from a
    shift, takes partly as a tilt that the gyro then keeps (seed-mean ``full`` error at the first update already
    -34 mdeg about camera x, against the registration's +35): the slow error common to the seeds.
    ``full``, 2 s landing from ground truth, seeds 0-3, mean ATE at 346x260 / 240x180 (bench ``ablation_seeds``):
    0 / 0.1 / 0.15 / 0.2 px gave 9.15 / 9.51, 7.81 / 9.42, 7.46 / 9.76, 7.36 / 10.30 mm (ARE 0.083 / 0.110 -> 0.077 /
    0.098 deg at 0.1; EKF backend 9.36 / 9.52 -> 7.94 / 9.64 mm); a trail growing with the normal speed instead,
    1.0 / 1.5 ms x speed, 8.36 / 9.45, 7.88 / 9.54 mm; with 0.1 here, ``fused_polarity_trail_px`` 0.1 8.03 / 9.99 mm.
    Bundled demos (``full``, ``--align none``, ATE RMSE) 0 -> 0.1: ``landing`` 15.98 -> 16.01 mm (ARE 0.188 ->
    0.170 deg), ``landing_dynamic`` 20.96 -> 15.64 mm, ``landing_fast`` 23.20 -> 24.04 mm; textured landing (seed 0)
    10.15 -> 10.13 mm (EKF 9.85 -> 9.12). The modes without fusion do not use it.

    Session 9, ``full``, seeds 0-3 (7.78 / 9.40 mm with the defaults). Buffer-zone points left out of registration:
    1215 / 24.2 mm (they hold the cross-flow direction). The TDF minimum at the truth against this trail model, closed
    loop, weighted by the final robust weights (``d`` = measured - model, + = the model trails too much): buffer
    points ``+0.23 - 1.29 v`` / ``+0.34 - 2.35 v`` px (``v`` normal speed, px/ms), ON ``-0.03 - 0.32 v`` / ``+0.11 -
    0.43 v``, OFF ``+0.09 - 0.29 v`` / ``+0.22 - 0.46 v`` at 346x260 / 240x180; correcting the buffer points by it
    (-0.13 px + 1.3 ms x speed, or -0.18 px + 1.8 ms) gave 9.69 / 10.05, 9.80 / 10.33 mm; a further trail of
    +0.3 / -0.3 ms x speed on ON/OFF points 8.46 / 9.68, 7.88 / 9.46, of -0.5 ms on buffer points 8.40 / 9.37; every
    trail shrunk linearly to 0 below 0.02 / 0.05 px/ms 7.84 / 9.47, 8.10 / 9.42 mm. A common trail offset as a 7th
    registration parameter (Schur complement at the converged pose): only ~12 % of its information independent of
    the pose, +0.03-0.10 px on average, 0.13-0.23 px from update to update; applied, 12.4 / 15.3 mm (per update),
    11.5 / 20.4 mm (averaged over ~50 updates). The offsets at the minimum are not what biases the pose: the knobs
    sit at an empirical optimum."""


def prior_widening(config: RegistrationConfig, pixel_mrad: float) -> float:
    """Factor on the fused modes' prior stds for a sensor whose pixel subtends ``pixel_mrad`` (see
    ``RegistrationConfig.fused_prior_reference_pixel_mrad``): 1 at or below the reference."""
    ref = float(config.fused_prior_reference_pixel_mrad)
    if not ref > 0 or not pixel_mrad > ref:
        return 1.0
    return float((pixel_mrad / ref) ** float(config.fused_prior_pixel_exponent))
