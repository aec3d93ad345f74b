"""Settings of the event-inertial SLAM: the paper's configurations (E-I-C1/C2/C3), the IMU initialisation, the
inertial local BA and the bridges over visual failures (:mod:`evpose.slam.inertial` re-exports both classes)."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from evpose.slam.inertial_init_visual import InitVisualConfig
from evpose.slam.inertial_window_config import InertialWindowConfig


class InertialConfiguration(str, enum.Enum):
    """The event-inertial configurations of the paper's Tables I and III (event-only is ``SlamMode.EVENT``)."""

    C1 = "c1"
    """E-I-C1, re-initialising: when tracking is lost a new map starts, with its own IMU initialisation."""
    C2 = "c2"
    """E-I-C2, continuous: once the IMU is initialised, visual failures are bridged by IMU propagation and the map
    keeps growing from the IMU-predicted keyframes; no new map is spawned (unless the bridge runs longer than
    ``max_bridge_s``). The paper's preferred configuration."""
    C3 = "c3"
    """E-I-C3: C2 with a fixed tiny-window size (``window.initial_events``, no adaptation) and no rejection of tiny
    windows by event rate (the paper's definition)."""


@dataclass
class InertialConfig:
    """IMU initialisation settings (event-inertial mode)."""

    configuration: InertialConfiguration = InertialConfiguration.C2
    """Which event-inertial configuration of the paper to run."""
    max_bridge_s: float = field(default=5.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "s"})
    """C2/C3: longest stretch of IMU-only propagation before the map is given up and a new one started (ORB-SLAM3's
    visual-inertial "recently lost" time is 5 s), seconds. 1 s split indoor seed 0 (E-I-C2) at 2.0 s into a second,
    never initialised map (RPE 0.018 m/m, 0.19 deg/m); with 5 s it is one map (0.0047 m/m, 0.018 deg/m; ATE 22.4 ->
    16.5 %). Indoor seeds 1-3 and landing seeds 0-7 were unchanged."""
    coast_s: float = field(default=0.4, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "s"})
    """C2/C3 before the IMU initialisation: longest stretch a map coasts through visual failures (gyro rotation,
    camera-frame velocity of its recent poses) before it is given up (0: lost at once, as before), seconds. On the
    simulated indoor room (E-I-C2, seeds 0-3, with ``min_inliers`` 8) 0.4 s raised the tracked time from 53-67 % to
    76-99 %, cut the maps from 10-14 to 1-5 and the RPE from 0.34-1.81 to 0.004-0.05 m/m; 0.1 s left 6-8 maps, 0.6 s
    sent one seed's ATE to 159 %, 1.0 s equalled 0.4 s on three seeds. Landing (seeds 0-7) unchanged."""
    rejoin_s: float = field(default=1.0, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "s"})
    """C2/C3 before the IMU initialisation: a map lost after coasting is continued by the next two-view map when that
    map's second keyframe comes within this long of the lost map's last pose (:mod:`evpose.slam.map_rejoin`; 0:
    never, every loss opens an independent map), seconds. Indoor E-I-C2 seeds 0-7: 0 -> 0.6 s: maps 1/1/5/1/3/1/5/5 ->
    1 on every seed, tracked 75-84 % -> 98-99.6 % on the split seeds, mean ATE 31.3 -> 18.8 % (worst 80.7 -> 24.7),
    RPE within 0.01 m/m and deg/m on 4 -> 7 seeds (seed 2 0.048 m/m, 0.112 deg/m -> 0.0078, 0.0016; seed 6 2.04 m/m
    -> 0.024 m/m, 0.0020 deg/m, still above; 0.0103 m/m, ATE 15.5 % once a map's first pose kept its own keyframe);
    seeds 0, 1, 3, 5 never lose a map and are bit-identical. 0.3 s left
    seed 2 three maps; 0.45, 0.8 and 1.0 s equalled 0.6 s on it (one re-join, after which the IMU initialisation
    reaches the map). Landing E-I-C2 seeds 0-23 never re-join: unchanged (mean ATE 0.89 %, RPE at most 0.0073 m/m,
    0.0021 deg/m). The scale the re-joined map gets rests on constant camera-frame velocity across the gap (true of
    the simulated room loop, not of every motion), and the IMU initialisation still misjudges the indoor scale (see
    ``max_scale_std_ratio``): ATE stays 15-25 %. Session 12, 0.6 -> 1.0 (the default since; ``/tmp/s12/slamin/exp.py``):
    E-I-C3 indoor seeds 0-7, whose fixed 8000-event MCIs lose maps for longer, ATE 23.0 / 20.8 / 90206 / 18.3 / 218.8 /
    21.9 / 20.3 / 85.7 % -> 23.0 / 20.8 / 20.5 / 18.3 / 29.5 / 34.8 / 20.3 / 30.0 %, tracked at least 45.0 -> 67.5 %,
    RPE at most 134.5 -> 0.230 m/m (seed 4; the rest at most 0.038 m/m): on seed 2 the map lost at 1.47 s was re-joined
    0.68 s later, and neither piece alone spanned the 1.2 s (``init_min_span_s``) the IMU initialisation needs, so
    both stayed in map units and were scored as metres. E-I-C2 indoor and landing seeds 0-7 unchanged (means 111.16 %
    and 1.16 % either way; indoor seed 5 is at 754 % before and after: its IMU initialisation is refused on every
    keyframe, scale estimate negative, so the map never becomes metric); E-I-C3 landing seeds 0-7 unchanged (1.42 %)."""
    rejoin_scale_depth_weight: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "weight"})
    """A re-join (``rejoin_s``) takes its scale partly from the scene depth: the weighted geometric mean of the two-view
    baseline against the coasted distance (weight ``1 - w``) and the median point depth of the lost map's newest
    keyframe seeing at least ``min_inliers`` of its points over that of the two-view map's first keyframe (weight
    ``w``; :func:`evpose.slam.map_rejoin.depth_scale`; 0: the baseline alone, 1: the depth alone), weight. Session 38
    (``/tmp/s38/ei38``: ``rjstat.py`` + ``rjana.py``): over the 56 re-joins of main's defaults on indoor 0-61 whose
    ideal scale the ground truth gives (the old segment's metres per unit over its last 0.3 s of keyframes against the
    new one's over its first 0.3 s), the baseline's scale is off by a median factor exp(0.44) (beyond 4x in 12 %), the
    depth's by exp(1.14) (43 %), their geometric mean by exp(0.70) (27 %); how far the two disagree does not tell when
    the baseline is wrong. The depth alone (w = 1, ``h.py`` + ``batch.sh`` + ``cmp.py`` tag ``dp8`` against main's
    ``m1``): indoor 0-19 / 20-39 / 40-53 / 54-61 / landing 0-23 within both RPE targets 19 / 19 / 14 / 8 / 24 (main
    20 / 19 / 14 / 8 / 24; seed 16 ran away, 21.9 m/m; seed 27 0.0100 -> 0.0111 m/m), seeds never IMU-initialised 9
    -> 11, landing bit-identical (no re-joins). Off."""
    rejoin_holds_velocity: bool = True
    """With ``coast_hold_velocity``: the two keyframes of a re-join's two-view map count as coasted poses (the coasting
    placed the first, and its scale put the second at the coasted distance), so a coast whose velocity span reaches
    back to them keeps the velocity of the coasting that placed them, as after a coast. Indoor seed 27 (main 0.01004
    m/m, its one map never IMU-initialised): a PnP pose on 8 inliers 50 ms after the re-join at 1.97 s stepped 112 mm
    for a true 23 mm, the 30 ms coasting velocity took the jump (0.58 -> 3.08 units/s), the 0.2 s coast ran on it and
    the next re-join (2.59 s) took its scale from it: the last 0.4 s moved 3-7 times too far and carry half of the
    seed's translation error (``/tmp/s38/ei38``: ``steperr.py``, ``diagrj.py``). Session 38 (``h.py`` + ``batch.sh``
    + ``cmp.py`` / ``pair.py`` / ``initc.py`` against main's ``m1``), alone (tag ``rh``): seed 27 0.00597 m/m and
    IMU-initialised at 1.91 s, but seeds 13 and 29 ran away (0.054 / 0.070 m/m: the visual BA of a young re-joined
    segment blew its scale up 55-80 times, see ``rejoin_scale_anchor``): within both targets 19 / 19 / 14 / 8 / 24
    (main 20 / 19 / 14 / 8 / 24), never initialised 9 -> 9, rotation RPE paired +0.0003 deg/m on each indoor set.
    With ``rejoin_scale_anchor`` 0.01 (tag ``rha``): within both targets 20 / 20 / 14 / 8 / 24 (seed 27 0.0055 m/m),
    never initialised 9 -> 7 (5 7 15 20 23 40 50), translation RPE paired -0.00073 +- 0.00036 / -0.00086 +- 0.00034 /
    +0.00018 +- 0.00027 / -0.00064 +- 0.00038 m/m (0-61 -0.00056 +- 0.00018, 35 better, 21 worse; worst 0.0100 ->
    0.0086; medians 0.0053 / 0.0051 / 0.0049 / 0.0048 -> 0.0049 / 0.0047 / 0.0044 / 0.0047), ATE -0.53 +- 0.57 points,
    rotation +0.00002 +- 0.00030 / +0.00053 +- 0.00034 / +0.00008 +- 0.00036 / +0.00027 +- 0.00066 deg/m (0-61 +0.00023
    +- 0.00018, 24 better, 32 worse; worst 0.0065 -> 0.0075; medians 0.0016 / 0.0016 / 0.0015 / 0.0014 -> 0.0016 /
    0.0016 / 0.0021 / 0.0016), tracked time unchanged, landing bit-identical; against the anchor alone (``an1``)
    translation -0.00029 +- 0.00011 m/m (22 better, 14 worse), rotation +0.00006 +- 0.00012. On with the anchor since
    session 38 (the lead): every recording then meets both targets and the translation gain is three standard errors;
    the rotation is a little worse on every indoor set (1.3 standard errors over 0-61, worst 0.0075 deg/m). The anchor's sigma with the hold:
    0.002 (``rha2``) 20 / 20 / 14 / 8 / 24 too, never initialised 9 -> 9, translation 0-61 -0.00047 +- 0.00021 m/m,
    rotation +0.00035 +- 0.00019 deg/m; 0.05 (``rha5``) lets indoor seed 16 run away (0.098 m/m, ATE 294 %): 19 / 20 /
    14 / 8 / 24."""
    rejoin_scale_anchor: float = field(default=0.01, metadata={"min": 0.0, "max": 1.0, "step": 0.005, "unit": "ratio"})
    """While the visual local BA's window starts at a re-joined segment's first keyframe, a range factor holds the
    distance between that keyframe (the fixed one) and the next, sigma this share of it
    (:func:`evpose.slam.inertial_guards.starts_at_rejoin`, ``TrackingConfig.ba_scale_anchor``'s factor; 0: none, the
    young segment's scale free), ratio: the re-join placed and scaled both, as a two-view map's own BA holds both of its
    keyframes fixed. With one fixed keyframe the young segment's scale is free, and over a few points the BA can blow
    it up (indoor seed 13 with ``rejoin_holds_velocity``: 55 times in one BA at 2.75 s, ``/tmp/s38/ei38/dbg13.py``;
    ``TrackingConfig.max_jump_depths`` cannot see it, the points move out with the keyframes). Session 38 (``h.py`` +
    ``batch.sh`` + ``cmp.py`` / ``pair.py`` / ``initc.py``, tag ``an1`` against main's ``m1``), 0.01: indoor 0-19 /
    20-39 / 40-53 / fresh 54-61 / landing 0-23 within both RPE targets 20 / 20 / 14 / 8 / 24 (main 20 / 19 / 14 / 8 /
    24: seed 27 0.01004 -> 0.0055 m/m, now IMU-initialised), seeds never IMU-initialised 9 -> 7 (0 5 17 23 27 30 32 40
    50 -> 7 14 20 23 29 40 50), translation RPE paired -0.00046 +- 0.00030 / -0.00059 +- 0.00039 / +0.00055 +- 0.00032
    / -0.00044 +- 0.00027 m/m (0-61: -0.00027 +- 0.00018, 30 better, 21 worse; worst 0.01004, seed 27 -> 0.00997, seed
    50, never initialised, 0.0068 before), rotation -0.00004 +- 0.00024 / +0.00066 +- 0.00032 / -0.00012 +- 0.00025 /
    -0.00004 +- 0.00064 deg/m (0-61 +0.00017 +- 0.00016; worst 0.0065 -> 0.0075), medians 0.0053 / 0.0048 / 0.0049 / 0.0047 m/m (main 0.0053 / 0.0051 /
    0.0049 / 0.0048) and 0.0015 / 0.0016 / 0.0011 / 0.0014 deg/m (main 0.0016 / 0.0016 / 0.0015 / 0.0014), tracked
    time unchanged (0.982 / 0.941 / 0.981 / 0.974); landing bit-identical (no re-joins). Holding both keyframes fixed
    instead (tag ``fx2``) fixes the second one's two-view rotation too: 19 / 20 / 14 / 8 / 24 (seed 16 0.0106 deg/m),
    rotation 0-19 +0.00116 +- 0.00048 deg/m (2 of 20 better), never initialised 9 -> 8. Alone the 40-53 translation
    and the 20-39 rotation are worse by about two standard errors; 0.01 is the default with ``rejoin_holds_velocity``
    (tag ``rha``, figures there), which alone lets young re-joined segments run away."""
    coast_velocity_span_s: float = field(default=0.03, metadata={"min": 0.005, "max": 0.5, "step": 0.005, "unit": "s"})
    """The coasting velocity is the mean over the newest poses spanning this long (consecutive MCIs are a few ms
    apart and their difference mostly noise), seconds. Not tuned: 0.03 s spans 5-6 MCIs indoors."""
    coast_hold_velocity: bool = True
    """Before the IMU initialisation, a coast whose velocity span reaches back to a coasted pose keeps the previous
    coast's velocity: across a coast and the PnP pose ending it the difference is the re-localisation's correction.
    Indoor E-I-C2 seed 3 re-localised at 0.56 s by 5.5 map units per true metre (visual steps 0.5) and coasted 0.4 s
    on it 160-170 deg off the true direction: scale -0.04 to -0.28 in all 78 initialisations (on the true keyframe
    poses the same solve gives 0.99-1.03 of the truth); seed 7's coasts ratcheted 0.34 -> 8.4 units per metre and ran
    away (RPE 0.98 m/m). ``/tmp/s35/ei35/h.py`` (= ``evpose slam`` + ``eval --atlas``), seeds within both RPE targets:
    alone 0-7 6 -> 7 of 8, held-out 8-39 24 -> 22 of 32; with ``coast_triangulate`` off 8 of 8 and 24 -> 24 (13, 29,
    38 gained, 17, 26, 32 lost on rotation), seeds never scaled 9 -> 5 of 40, above 0.01 m/m 6 -> 3 (the multi-map
    11, 22, 24), above 0.01 deg/m 9 -> 8, median 0.0026 -> 0.0039 deg/m. Landing 0-23: no such coast, bit-identical. Session 36, both on with the
    guards ``discard_lost_young_s`` / ``init_max_gyro_deg`` / ``ba_gyro_prior_chain`` (``/tmp/s36/ei36/h36.py``,
    against those guards alone): indoor 0-19 17 -> 20 of 20, 20-39 20 -> 18 (26 and 32 lost on rotation, 0.025 and
    0.014 deg/m), fresh seeds 40-53 14 -> 14; no run away any more (worst 0.0075 m/m, before 99.6 m/m on seed 1),
    median rotation RPE 0.0023 -> 0.0018 deg/m over 0-53 (better medians of both RPEs on each of 0-19, 20-39 and 40-53;
    40-53 rotation 0.0029 -> 0.0013, 10 of 14 better), tracked time unchanged; landing 0-23 bit-identical (the lead,
    ``/tmp/s36/lead/eic/h36.py``). So on since session 36, with ``coast_triangulate`` off: 52 of 54 indoor seeds within
    both targets against 51, and no run-away."""
    coast_triangulate: bool = False
    """Triangulate points from keyframes coasted before the IMU initialisation (off: they only observe, as event-only
    coasts with ``TrackingConfig.coast_triangulate``): PnP on them carries the coast's error on (seed 7's visual steps
    grew to 160-4000 units per metre after coasts at 6.8-8.4). Off alone, indoor seeds 0-7 6 -> 7 of 8 (3, 6, 7 now
    initialised; 4 0.0016 -> 0.0176 deg/m), 8-16 7 -> 6 of 9; see ``coast_hold_velocity``, with which it is off since session 36. Landing bit-identical."""
    ba_gyro_prior_chain: bool = True
    """The visual local BA's gyro rotation priors (``ba_gyro_prior_uninit_deg``) join consecutive keyframes *of the
    BA*, chaining the gyro across keyframes that see no point, and the BA window starts at its oldest keyframe the BA
    holds, so the fixed one anchors it (:func:`evpose.slam.inertial_guards.bundle_keyframes`, ``anchored_window``).
    Off (before): a pair with a keyframe the BA leaves out (a coasted one) got no prior, and when that keyframe was the
    window's fixed one nothing was fixed: indoor seed 6 (with the two options below) turned its window 8.8 deg with
    29 points, and the poses between the coasted keyframe and the next took the turn as one step (0.022 deg/m).
    Measured as a set with ``init_max_gyro_deg`` and ``discard_lost_young_s``, see there; with
    ``discard_lost_young_s`` alone (``init_max_gyro_deg`` 0) indoor seeds 0-19 / 20-39 / 40-53 within both RPE targets
    16 / 16 / 12 (main's defaults 16 / 14 / 13), landing 0-23 bit-identical, tracked time unchanged."""
    init_max_gyro_deg: float = field(default=3.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """A two-view start (a new map, or one re-joining the map lost while coasting) whose relative rotation is farther
    than this from the gyro's over the same interval is refused like a failed attempt (0: never,
    :mod:`evpose.slam.inertial_guards`), degrees. Indoors one such step carried most of a seed's rotation RPE (seed 30
    13.3 deg, seed 3 8.8, seed 13 4.4 and 3.7, seed 38 5.4); landing two-view starts are 0.6-2.7 deg off the gyro
    (session 12) and none is refused. E-I-C2, ``/tmp/s36/ei36/h36.py`` (= ``evpose slam --mode event-inertial`` +
    ``evpose eval --atlas``), seeds within both RPE targets (0.01 m/m, 0.01 deg/m), main's defaults ->
    ``discard_lost_young_s`` 0.1 -> + this at 5 deg -> + ``ba_gyro_prior_chain`` (c5) -> this at 3 deg (c3, the
    defaults): indoor 0-19 16 -> 17 -> 18 -> 19 -> 17, 20-39 14 -> 16 -> 18 -> 19 -> 20, the fresh seeds 40-53
    (``/tmp/s35/lead/rec``) 13 -> 12 (c5) -> 14 (c3); all 54: 43 -> 51 (rotation target 45 -> 53, translation 47 -> 52), median
    rotation RPE 0.00236 -> 0.00233 deg/m (c5 0.00269). Left
    (c3): seed 1 runs away in a pre-initialisation coast (99.6 m/m; 0.0049 before), seed 3 0.0152 m/m (coasts, as
    before), seed 7 0.0120 deg/m (a re-join 2.6 deg off). Landing 0-23 bit-identical in every step. 5 deg left
    re-joins 3.9-4.4 deg off in seeds 43 and 45 (held-out, 0.0129 deg/m; 45 then ran away in a coast, 0.058 m/m).
    The cost is tracked time: a refused start waits for the next one that agrees, and indoors those can be far apart
    (seed 1's first map starts at 0.93 s instead of 0.03 s): indoor 0-39 mean tracked 96.7 -> 92.4 % (against
    ``discard_lost_young_s`` alone; seeds 1, 5, 7, 27, 29, 30 lose 17-30 points; least 68.0 -> 66.3 %), 40-53 98.3 -> 98.1 %, landing unchanged. Resolving the
    two-view start with the gyro's rotation instead of refusing it (session 12 tried a re-solve at 0.5-5 deg, mixed):
    ``init_gyro_two_view`` (session 37, off). E-I-C3 never refuses: its fixed 8000-event windows' starts were refused so
    often that indoor seeds 0-3 stayed uninitialised and split (RPE 0.019-0.029 -> 0.027-0.227 m/m, all off the target
    either way; landing 0-3 bit-identical). E-I-C1 with the three guards: landing 0-3 bit-identical, indoor 0-3 10-16
    -> 1-3 maps, RPE 0.19-0.44 -> 0.033-0.056 m/m, 0.40-6.3 -> 0.007-0.054 deg/m (off the targets either way).
    With session 36's other defaults (the coast options too), indoor 0-19 / 20-39 / 40-53 and landing 0-23 within both
    RPE targets (``/tmp/s36/lead/eic/h36.py``, ``cmp.py``): 3 deg 20 / 18 / 14 / 24 (tracked 0.939 / 0.910 / 0.981 /
    0.989), 2.5 deg 18 / 18 / 14 / 24 (0.927 / 0.886 / 0.980 / 0.989; 1 landing seed changed), 2 deg 19 / 19 / 14 / 24
    (0.911 / 0.876 / 0.949 / 0.983; 2 changed): tighter refuses more starts for no more seeds."""
    init_gyro_two_view: bool = True
    """Resolve a two-view start (a new map, or one re-joining the map lost while coasting) with the gyro's rotation
    between the two views instead of refusing it (:mod:`evpose.slam.gyro_two_view`): the relative rotation is the gyro's
    (bias-corrected once known, through ``T_cam_imu``), only the translation direction is estimated (2-point RANSAC,
    then a refinement with the gyro rotation as a prior of ``init_gyro_two_view_sigma_deg``), then the points are
    triangulated as before. Applies to the starts the decomposition accepted that are at least
    ``init_gyro_two_view_min_deg`` off the gyro (those beyond ``init_max_gyro_deg`` included: resolved, not refused); a
    start the gyro solution cannot triangulate goes on to the guard (``init_gyro_two_view_refuse_unsolved``). E-I-C3 is
    left alone (as the guard). On since session 37 (the lead), with ``init_gyro_two_view_min_deg`` 1. On the synthetic
    scene-switch recording of ``tests/slam/test_configurations.py`` (C2, ``init_keyframes`` 50, never IMU-initialised)
    it had looked as if every start (0 deg) spoilt a start the decomposition had within 0.3 deg of the gyro (whole run
    1.29 -> 15.0 %, ``/tmp/s37/lead/rj.py``; from 1 deg that run is the same as off), but that start was the better one
    (gx37, ``/tmp/s37/gx37/d1.py``: rotation 0.025 against 0.344 deg off the truth, translation direction 0.78 against
    7.51 deg) and the live poses before the switch as good (0.2-4.5 cm off): the run differed by chaos, and a KLT track
    that outlived the scene switch was triangulated across the re-join against the other scene's keyframe 0, whose point
    slid the re-joined segment's scale 17 times at its last keyframe (see
    :func:`evpose.slam.local_map.triangulate_new_points`, which now checks such pairs: whole run 1.25 % at 0 deg, 1.29 %
    off; before the switch 0.58 / 0.38 %, ``/tmp/s37/gx37/rj2.py``). With that check at 0 deg (``/tmp/s37/gx37/h.py``,
    tag ``v7`` against ``g7``), indoor 0-19 / 20-39 / 40-53 within both targets 20 / 19 / 14 as before (seed 27 0.0136
    m/m), rotation RPE +0.0003 +- 0.0004 / +0.0003 +- 0.0002 / -0.0001 +- 0.0001 deg/m, 35 of 54 seeds unchanged. At 1
    deg before that check (tag m1, ``/tmp/s37/lead/eic/batch.sh`` + ``/tmp/s37/ei37/cmp.py``): indoor 0-19 / 20-39 /
    40-53 / fresh 54-61 / landing 0-23 within both targets 20 / 19 / 14 / 8 / 24 (main without it 20 / 18 / 14 / 8 / 24;
    the one miss seed 27 at 0.01004 m/m), tracked 0.982 / 0.941 / 0.981 / 0.974 / 0.989 (least 0.842 / 0.666 / 0.840 /
    0.852 / 0.982; without it 0.939 / 0.910 / 0.981 / 0.952 / 0.989, least 0.697 / 0.663 / 0.840 / 0.688), rotation RPE
    paired -0.0003 +- 0.0003 / -0.0025 +- 0.0013 / +0.0003 +- 0.0002 / +0.0000 +- 0.0005 / +0.0000 +- 0.0000 deg/m, the
    rotation target met on every indoor seed; seeds never IMU-initialised 4 / 1 / 2 / - / 0 -> 3 / 4 / 2 / - / 0; 12 of
    the 24 landing runs bit-identical. 0 and 1 deg give the same counts. ei37's figures at 0 deg and the other settings,
    session 37 (``/tmp/s37/ei37/h.py`` = ``evpose slam --mode event-inertial`` + ``evpose eval --atlas``, ``batch.sh``,
    ``cmp.py``, ``initc.py``), seeds within both RPE targets (0.01 m/m, 0.01 deg/m) on indoor 0-19 / 20-39 / 40-53 /
    landing 0-23, main's defaults (tag ``rv``) 20 / 18 / 14 / 24, mean tracked 0.939 / 0.910 / 0.981 / 0.989 (least
    0.697 / 0.663 / 0.840 / 0.982), seeds never IMU-initialised 4 / 1 / 2 / 0. On, by
    ``init_gyro_two_view_min_parallax_deg``: 0.4 deg (g7) 20 / 19 / 14 / 24, tracked 0.983 / 0.941 / 0.981 / 0.989
    (least 0.842 / 0.666 / 0.840 / 0.982), never initialised 2 / 4 / 2 / 0, the one miss seed 27 at 0.01004 m/m; 0.3 deg
    (g6) 19 / 19 / 13 / 24, tracked 0.971 / 0.945 / 0.981 / 0.989, misses 2, 27 and 50 on translation (0.047, 0.010,
    0.015 m/m); 0.5 deg (g2, same solver before a speed-up) 20 / 19 / 14 / 24, tracked 0.969 / 0.941 / 0.981, seed 26
    left at 0.013 deg/m. Every setting meets the rotation target on all 54 indoor seeds (main: 52): seeds 26 and 32 go
    to 0.0015 / 0.0017 deg/m, mean rotation RPE 20-39 -0.0025 +- 0.0013 deg/m (13 of 20 better); 40-53 +0.0003 +- 0.0002
    (0.4 deg). The misses are all translation, in maps the IMU initialisation never reached (their scale is the first
    start's and the re-joins' coasting, and a start resolved at 0.3-0.5 deg of true parallax can set it several times
    too large: seed 2 at 0.3 deg, its decomposition 25.5 deg off the gyro). Landing 0-23: all 24 within both targets,
    none bit-identical, medians 0.0027 -> 0.0025 m/m and 0.0013 deg/m. Fresh indoor seeds 54-61 (``/tmp/s37/ei37/rec``,
    simulated after the choice): 8 / 8 both ways, tracked 0.952 -> 0.974 (least 0.688 -> 0.852), rotation RPE +0.0005 +-
    0.0006 deg/m (3 of 8 better), medians 0.0051 -> 0.0050 m/m, 0.0014 -> 0.0015 deg/m. Resolving only the starts the
    guard refuses (``init_gyro_two_view_min_deg`` 3, g8) wins the same tracked time (0.982 / 0.941 / 0.982 / 0.974) and
    leaves landing bit-identical, but not the rotation: 20 / 17 / 14 / 8 / 24, seeds 26 and 32 unchanged (their re-joins
    are 1.5-3.0 deg off, under the guard) and seed 35 running away on translation (0.153 m/m, never initialised). With
    ``init_gyro_two_view_refuse_unsolved``: 0.3 deg 19 / 19 / 14 / 24, 0.5 deg 19 / 18 / 12 / 24 (tracked 0.963 / 0.928
    / 0.969). Cost: 4 ms of CPU per resolved start (matches of 100 points, ``/tmp/s37/ei37/chk_many.py``); the tracking
    thread's CPU per MCI on indoor 26 / 55 (CLI) median 9.1 / 8.7 ms against 8.5 / 8.5 off."""
    init_gyro_two_view_min_deg: float = field(default=1.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """With ``init_gyro_two_view``: starts whose decomposed rotation is closer than this to the gyro's keep it (0:
    every start takes the gyro's rotation), degrees. 0, 1 and 3 measured (see ``init_gyro_two_view``): 1 keeps the
    synthetic scene-switch run's start that 0 spoils and gives the seeds 0's counts; 3 leaves seeds 26 and 32 failed."""
    init_gyro_two_view_min_parallax_deg: float = field(default=0.4, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "deg"})
    """With ``init_gyro_two_view``: the median parallax a gyro-resolved start needs, in place of
    ``InitializationConfig.min_parallax_deg_inertial`` (1 deg), degrees. The decomposition's rotation error passes
    for parallax: indoor seed 26's starts, accepted at 1.3-1.7 deg, have 0.37-0.88 deg with the gyro's rotation, so
    the 1 deg bar refused every one of them. 0.3 / 0.4 / 0.5 measured, see ``init_gyro_two_view``."""
    init_gyro_two_view_max_direction_std_deg: float = field(default=0.0, metadata={"min": 0.0, "max": 45.0, "step": 0.5, "unit": "deg"})
    """With ``init_gyro_two_view``: a gyro-resolved start under ``init_gyro_two_view_min_parallax_deg`` is taken when its
    translation direction's standard deviation is at most this (the matches' Sampson information with the gyro rotation
    prior, the noise's own share taken out, :func:`evpose.slam.gyro_two_view.translation_direction_std_deg`; 0: the
    parallax bar alone), degrees. On synthetic matches the std is within 0.6-1.6x the solver's actual scatter
    (``tests/slam/test_direction_std_s39.py``); on real indoor starts (``/tmp/s39/ei39/cal.py``, seeds 2 5 7 15 26 50)
    10 of the 15 the 0.4 deg bar accepts and 9 of the 13 under it are undetermined, the rest 2.1-9.8 deg. Session 39
    (ei39, tag ``ds4`` against main's ``rha``), 4 deg: within both RPE targets unchanged (indoor 62 of 62, landing 24 of
    24, landing bit-identical), indoor 0-61 translation RPE -0.00002 +- 0.00006 m/m, rotation -0.00008 +- 0.00006 deg/m,
    the same 7 runs never IMU-initialised (refused for the map's scale jumps at re-joins, not parallax). Neutral, so off."""
    init_gyro_two_view_refuse_unsolved: bool = False
    """With ``init_gyro_two_view``: a start the gyro's rotation cannot triangulate (too few points, or less parallax
    than ``init_gyro_two_view_min_parallax_deg``) is refused; off, the decomposition's own start goes on to the
    ``init_max_gyro_deg`` guard. On lost seeds to translation at 0.5 deg (see ``init_gyro_two_view``)."""
    init_gyro_two_view_sigma_deg: float = field(default=0.1, metadata={"min": 0.001, "max": 10.0, "step": 0.01, "unit": "deg"})
    """With ``init_gyro_two_view``: the gyro rotation prior's standard deviation in the two-view refinement, degrees
    (over 0.01-0.1 s a bias of a few mrad/s turns the camera by hundredths of a degree). Not tuned."""
    discard_lost_young_s: float = field(default=0.1, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "s"})
    """A map lost before the IMU initialisation reached it, whose poses span less than this, is discarded (emptied; no
    trajectory written) instead of kept in the atlas, as ORB-SLAM3 resets a map lost with under 10 keyframes (0: kept,
    :mod:`evpose.slam.inertial_guards`), seconds. The paper's RPE averages each map's error per metre over the maps,
    so the 2-3 cm first maps of indoor seeds 11, 22 and 24 (3-4 poses, lost after 17-28 ms) failed both targets
    (4.48 m/m and 208 deg/m, 0.163 / 0.079, 0.225 / 0.056); discarded, each meets both (0.0058 / 0.0068, 0.0054 /
    0.0044, 0.0050 / 0.0028) and the rest is bit-identical to before (7 of 40 seeds changed: these three, and four whose
    dropped map was too short to be scored, figures unchanged; 30 -> 33 of 40 within both targets). Landing 0-23 bit-identical. 0.1 s is not tuned: no map of
    indoor seeds 0-39 was lost between 0.03 and 0.3 s of age (these runs and the defaults'). See ``init_max_gyro_deg`` for the set."""
    coast_ba: bool = False
    """Run the visual local BA on keyframes made while coasting. Off: those keyframes carry few points, and a BA with
    one fixed keyframe slid along the scale (indoor seed 3: map scale 3e-5 of the truth, ATE 30852 %); with it off,
    indoor seeds 0-3 (coast 0.2 s, ``min_inliers`` 8) gave 20-27 % ATE."""
    min_inliers: int = field(default=8, metadata={"min": 0, "max": 200, "step": 1, "unit": "points"})
    """Pose inliers event-inertial tracking needs, before the IMU initialisation, instead of
    ``TrackingConfig.min_inliers`` (0 keeps that): the gyro prior holds the rotation, so fewer points place the camera,
    points. Indoor (E-I-C2, seeds 0-3, coasting 0.2 s) 12 -> 8 lowered the mean ATE from 44 % to 24 % and lifted the
    tracked time from 54-73 % to 71-79 %; 6 gave 33 %. Applied to IMU-initialised maps as well it cost landing
    (seeds 0-7) 0.04 points of mean ATE, so it stops at the initialisation."""

    init_keyframes: int = field(default=6, metadata={"min": 3, "max": 50, "step": 1, "unit": "keyframes"})
    """Keyframes the map needs before the IMU is initialised, keyframes."""
    init_min_span_s: float = field(default=1.2, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "s"})
    """Time the keyframes must span before initialising, seconds."""
    init_min_gap_s: float = field(default=0.3, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "s"})
    """Keyframes used by the initialisation are thinned to at least this spacing: the acceleration signal grows with the square of the gap while visual position noise does not, and a noisy displacement regressor biases the scale towards zero, seconds."""
    init_trailing_fallback: bool = False
    """When the IMU initialisation over all of a map's keyframes is refused, try it once more over the keyframes of the
    newest ``init_min_span_s`` (at least ``init_keyframes``). Session 39 (``/tmp/s39/ei39`` ``h.py`` + ``pair.py``, tag
    ``tf`` against ``rha``): the 7 indoor runs never initialised (5 7 15 20 23 40 50) 7 -> 0, RPE unchanged, landing
    bit-identical; off because what it initialises is 0.03-0.18 of the true scale (``trail.py``): indoor ATE without
    scale correction 16.96 -> 16.94 % (-0.02 +- 0.45 points; seed 20 4.5 -> 23.1 %)."""
    init_visual: InitVisualConfig = field(default_factory=InitVisualConfig)
    """The initialisation over visually tracked keyframes of one visual segment (:mod:`evpose.slam.inertial_init_visual`)."""
    refine_after_s: float = field(default=1.2, metadata={"min": 0.0, "max": 30.0, "step": 0.1, "unit": "s"})
    """This long after the IMU initialisation, scale and gravity are re-estimated once over all keyframes of the map
    (the initialisation's alignment, now on a metric map twice as long), and the map is rescaled, re-aligned and given
    a full inertial BA (ORB-SLAM3 refines its initialisation in the same way as the map grows; 0: never), seconds. The
    initialisation's four thinned keyframes left landing seed 7 at 1.65 times the true scale (ATE 13 %). Landing
    E-I-C2 seeds 0-7 (with the gyro-bias priors below): mean ATE 4.35 -> 1.09 %, worst 17.9 -> 2.4 %, RPE max 0.0109
    -> 0.0055 m/m; 1.0 s gave a mean of 1.08 %, 1.5 s 1.07 %. On the indoor maps the alignment is mostly refused
    (negative scale); the few it accepted shrank the map 5-30 times the wrong way (``refine_min_scale`` refuses them)."""
    refine_min_scale: float = field(default=0.33, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """A scale refinement (``refine_after_s``) that would shrink the map below this share of its size is refused (0: no
    test), ratio: the alignment's noisy displacement regressor biases the scale towards zero (``init_min_gap_s``). Session
    39 (``/tmp/s39/ms39`` ``trace.py``): the refinements accepted on indoor seeds 2 / 9 / 18 (scales 0.204 / 0.139 / 0.031)
    took the map from 1.12 / 4.23 / 2.43 to 5.36 / 30.4 / 6.58 true metres per map unit; landing seeds 0-3 refine by
    0.78-0.94. 0.33 (not tuned; tag ``rm33`` against main's ``rha``): indoor 0-61 ATE without scale correction 16.96 ->
    16.23 % (-0.73 +- 0.27 points, 10 better, 1 worse: seed 56 7.93 -> 13.36), RPE translation -0.00001 +- 0.00004 m/m,
    rotation -0.00018 +- 0.00009 deg/m, all 62 within both targets; landing 0-23 and 24-35 bit-identical. On."""
    refine_max_residual_ratio: float = field(default=0.2, metadata={"min": 0.001, "max": 1.0, "step": 0.001, "unit": "ratio"})
    """``max_residual_ratio`` of the refinement: the map it corrects is already metric, and a scale error since the
    initialisation is what leaves the residual (landing seeds 2, 6, 7: 6.4, 2.8, 8.6 %; the 0.02 of the first
    initialisation refused all three), ratio. Not tuned."""
    init_gyro_bias_sigma: float = field(default=0.003, metadata={"min": 0.0, "max": 0.5, "step": 0.001, "unit": "rad/s"})
    """Prior sigma (per axis, zero mean) of the gyroscope bias in the IMU initialisation (0: no prior, the bias is the
    mean rotation disagreement per second between the keyframes and the gyro), rad/s. Without it the visual rotation
    errors became the bias: 0.017-0.073 rad/s estimated on landing seeds 0/1/7 and indoor seeds 0/1/3, where the
    simulated gyro has 0.001-0.004 (its bias sigma is 0.002); a 0.07 rad/s bias turns each 25 ms step by 0.1 deg. The
    simulator's MEMS part has 0.002 rad/s per axis; 0.003 leaves room for a worse one. Effect in the comments of
    ``gyro_bias_sigma``."""
    init_rotation_sigma_deg: float = field(default=0.5, metadata={"min": 0.01, "max": 10.0, "step": 0.01, "unit": "deg"})
    """Error of the visual rotation between two keyframes assumed by that prior (uninitialised maps were off by 0.1-1
    deg per step indoors), degrees. 0.2 gave the same landing mean ATE (seeds 0-7) and a worse indoor seed 0."""
    max_gravity_error: float = field(default=0.25, metadata={"min": 0.01, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """The unconstrained gravity estimate must have a norm within this share of 9.81 m/s^2, ratio."""
    max_scale_std_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "ratio"})
    """The initialisation (and its refinement) is refused when the standard error of the scale, from the covariance of
    the |g|-constrained least squares, exceeds this share of the scale (0: no test), ratio. The residual test cannot
    see a scale the keyframes do not determine: a scale near zero fits the IMU rows, whose free velocities absorb the
    IMU deltas. On the simulated room (E-I-C2, seeds 0, 1, 3) the accepted initialisations had 0.06, 0.015 and 0.017 of
    the true scale and standard errors of 133 %, 733 % and 158 %; on the landing (seeds 0-7) the accepted ones had
    4-13 % (refinements 2-13 %). 0.2 leaves landing bit-identical; indoors it refuses every attempt, the maps stay
    unscaled and, coasting no further, split (seeds 0-3: mean ATE 19.3 -> 23.5 %, RPE of seeds 0/1 0.0065/0.0061 ->
    0.019/0.016 m/m), so it stays off until the indoor front end can give the initialisation a determined scale. (With
    the true scale given to the initialisation, from ground-truth keyframe poses, seeds 0/1/3 came out no better, ATE
    20.2/24.7/21.2 %: the coasted keyframes' points and the 25 ms local inertial BA windows of keyframes made at every
    MCI shrink the velocity from 1.25 to 0.08 m/s within the first BAs.) Session 8, indoor E-I-C2: before the
    initialisation 47 of seed 0's 62 keyframes were coasted and the map's scale drifted threefold across them (2.0 ->
    6.8 m per map unit); the accepted alignments were 13-65 times too small (seeds 0/1/2: 0.126/8.6/23.6 against
    2.0/561/310), passing the residual test because gravity dominates the IMU deltas; alignments on 0.2-0.6 s of the
    visually tracked keyframes alone came out negative (ground-truth poses there give the scale within 1 %). Given the
    true scale and gravity direction at the initialisation (from ground truth), seed 0 still ended at 21 % ATE: the full
    inertial BA pulled the velocity from 1.24 to 0.30 m/s and the accelerometer bias to 0.18 m/s^2 to fit the drifting
    map (without that BA 45 %, the 25 ms local windows letting the velocity wander). With ``rejoin_s`` 0.6 (maps no
    longer split) 0.2 still refuses every indoor attempt: seeds 0-7 mean ATE 17.6 -> 112 %, RPE targets met on 0 of 8
    instead of 7."""
    max_motion_residual_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.01, "unit": "ratio"})
    """The initialisation (not its refinement) is refused when the RMS residual of the alignment exceeds this share of
    the RMS of the IMU deltas with gravity removed (``ImuInitResult.motion_residual_ratio``; 0: no test), ratio.
    E-I-C2 accepted initialisations: landing seeds 0/1 0.025/0.026 (scale right within 2 %), indoor seeds 0/1
    0.196/0.129 (seed 0 at 2.11 s with 0.00018 m per map unit, the first 2 s of the trajectory collapsing to a point;
    seed 1 at 1.22 s, the map's pre-initialisation scale drifting 0.13-0.33 of the truth). 0.1 leaves landing seeds
    0/1 bit-identical, but indoors nothing better comes: seed 0 is never initialised (ATE 16.8 -> 72089 %, the map
    unscaled), seed 1 initialised at 1.29 s, ATE 17.7 -> 19.6 %, RPE 0.0118 -> 0.0177 m/m. Indoors 60 % of the MCIs
    are bridged (coasted before, IMU-propagated after the initialisation), and the visual keyframes between them do
    not fix a scale: the initialisation needs a better indoor front end, not a stricter test. Off."""
    max_residual_ratio: float = field(default=0.02, metadata={"min": 0.001, "max": 0.5, "step": 0.001, "unit": "ratio"})
    """RMS residual of the alignment over the RMS of the IMU deltas above which initialisation is refused, ratio."""
    velocity_from_imu: bool = False
    """A keyframe of a metric map without a velocity estimate starts the inertial BA from the velocity the IMU
    propagates from its predecessor's, instead of the finite difference of the two keyframes' positions (indoor
    keyframes come a few ms apart and their positions jump by centimetres where tracking re-localises). Measured with
    ``rejoin_s`` 0.6: landing E-I-C2 seeds 0-15 mean ATE 0.99 -> 0.95 % (seed 7 1.93 -> 1.01, seed 1 1.08 -> 0.58,
    seed 2 0.63 -> 0.98, seed 4 0.48 -> 0.78), RPE worst unchanged 0.0073 m/m; indoor seeds 0-3 mean ATE 17.3 -> 18.5 %
    (seed 0 15.1 -> 20.6), all four within the RPE targets either way. Within the spread of single changes: off."""
    ba_velocity_prior_sigma: float = field(default=0.5, metadata={"min": 0.001, "max": 5.0, "step": 0.005, "unit": "m/s"})
    """Sigma of the prior holding the velocity of the oldest keyframe of an inertial BA window at its last estimate
    (the window's first pose is fixed; this is what carries the metric scale from one window to the next), m/s.
    Indoor E-I-C2 seed 0 (default: ATE 16.80 %, RPE 0.0075 m/m, 0.0191 deg/m): 0.05 -> 21.83 %, 0.0117 m/m, 0.0191
    deg/m. There the IMU initialisation is accepted only at 2.11 s, with 0.00018 m per map unit (the visual map's
    scale is 1-2 m per unit): the first 2 s of the metric trajectory collapse to a point, and what the local BA does
    afterwards matters little (see ``max_motion_residual_ratio``)."""
    ba_min_span_s: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "s"})
    """An inertial local BA window spanning less than this is extended back by up to ``ba_span_keyframes`` older
    keyframes, thinned in time (:func:`evpose.slam.inertial_ba.spanning_window`; 0: the newest
    ``TrackingConfig.local_window`` keyframes only), seconds. Indoor keyframes come every 4-6 ms, so six of them span
    ~25 ms, too short for the IMU factors to hold the velocity (session 8: it shrank from 1.25 to 0.08 m/s within the
    first BAs). Indoor E-I-C2 seed 0: 0.3 (4 older keyframes) -> ATE 16.80 -> 18.17 %, RPE 0.0075 -> 0.0089 m/m,
    0.0191 -> 0.0256 deg/m; not the bottleneck while the initialisation's scale is wrong (``ba_velocity_prior_sigma``).
    Landing keyframes come ~77 ms apart (six span ~0.4 s), so 0.3 would rarely extend a window there (not measured)."""
    ba_span_keyframes: int = field(default=4, metadata={"min": 0, "max": 20, "step": 1, "unit": "keyframes"})
    """Most older keyframes ``ba_min_span_s`` adds to a window, keyframes."""
    carry_mci_scale: bool = True
    """After every BA of an event-inertial map (and the full inertial BA of the IMU initialisation and its
    refinement), the MCI poses' translations relative to their keyframe are scaled by how much the BA stretched the
    keyframe path around that keyframe (:mod:`evpose.slam.inertial_trajectory`); off: they keep the scale they were
    tracked in. Session 12, with ``ba_gyro_prior_min_points`` 0: indoor E-I-C2 seeds 0-7 all within both RPE targets
    either way, worst 0.0092 -> 0.0067 m/m (seed 2's first 0.25 s of MCIs had stood 14 cm per step off); the four
    perturbations named at ``ba_gyro_prior_min_points`` x seeds 0-7: runs missing a target 10 -> 4 of 32 (seeds 1 and 2,
    0.0192 / 0.0120 / 0.0227 / 0.0363 / 0.0329 / 0.0425 -> 0.0047 / 0.0061 / 0.0055 / 0.0094 / 0.0063 / 0.0062 m/m).
    Left: seed 6 (two of them, see there), seed 4 with ``ba_huber_px`` 2.1 (a second map lost 13 ms after its
    two-view initialisation, too young to coast: 0.162 m/m over its 2 cm), seed 3 with ``reprojection_threshold_px``
    2.6 (the initialisation refused on all 95 keyframes, the map in its own units: 6.3 m/m). Landing E-I-C2 seeds
    0-7: mean ATE 1.09 -> 1.06 %, RPE at most 0.0050 m/m, 0.0017 deg/m. Holding the scale of the visual BA before the
    initialisation instead (``TrackingConfig.ba_scale_anchor`` 0.02 on event-inertial maps): landing 0.86 %, but
    indoor seed 6 6511 % ATE and 1.97 m/m, seed 4 0.0118 deg/m (not kept). This with ``ba_gyro_prior_min_points`` 0,
    against the defaults before: E-I-C3 landing seeds 0-3 1.02 -> 1.19 % (seed 1 0.81 -> 1.52), RPE at most 0.0033 m/m
    and 0.0017 deg/m; E-I-C3 indoor seeds 0-3 0.019-0.033 -> 0.022-0.047 m/m (off that target either way), 0.0033-0.074
    -> 0.0036-0.048 deg/m; E-I-C1 landing seeds 0-3 4.33 -> 4.23 %, seed 3 0.0032 -> 0.0110 deg/m (a visual pose 2.6
    deg off the gyro kept after the initialisation, just before the map is lost; seeds 0 and 2 off the translation
    target either way); E-I-C1 indoor seeds 0-3 (13-18 maps) 3.8-6.4 -> 0.35-0.58 deg/m, 0.23-0.43 -> 0.30-1.07 m/m;
    event-only runs unchanged; per-MCI main-thread CPU (indoor seed 0, alternated in one process, 4 runs each)
    17.83 -> 16.31 ms median."""
    inertial_ba: bool = True
    full_ba_after_init: bool = True
    """Right after a successful initialisation, run the inertial BA once over all keyframes of the map."""
    """After IMU initialisation, local BA adds IMU preintegration factors between keyframes (gtsam ImuFactor)."""
    acc_noise: float = field(default=0.01, metadata={"min": 1e-4, "max": 1.0, "step": 1e-3, "unit": "m/s^2/sqrt(Hz)"})
    """Accelerometer white-noise density used by the inertial BA and IMU propagation (gtsam's continuous-time
    covariance; about five times a consumer MEMS part's), m/s^2/sqrt(Hz)."""
    gyro_noise: float = field(default=0.001, metadata={"min": 1e-5, "max": 0.1, "step": 1e-4, "unit": "rad/s/sqrt(Hz)"})
    """Gyroscope white-noise density used by the inertial BA and IMU propagation (about five times a consumer
    MEMS part's: looser lets the images bend the gyro's rotations between keyframes), rad/s/sqrt(Hz)."""
    acc_bias_sigma: float = field(default=0.02, metadata={"min": 1e-4, "max": 1.0, "step": 1e-3, "unit": "m/s^2"})
    """How far one inertial BA may move the accelerometer bias from its last estimate (1 sigma), m/s^2."""
    gyro_bias_sigma: float = field(default=1e-4, metadata={"min": 1e-5, "max": 0.1, "step": 1e-5, "unit": "rad/s"})
    """How far one inertial BA may move the gyroscope bias from its last estimate (1 sigma), rad/s. A MEMS gyro's bias
    walks by about 4e-5 rad/s in 3 s (the simulator's 2e-5 rad/s^2/sqrt(Hz)); with 1e-3 per BA the full BA after the
    initialisation pulled indoor seed 0's bias from 0.005 back to 0.04 rad/s. E-I-C2 with ``init_gyro_bias_sigma``
    0.003 and the scale refinement: indoor seed 0 RPE 0.0056 m/m, 0.0128 deg/m (1e-3) -> 0.0065 m/m, 0.0046 deg/m (1e-4),
    seeds 1 and 3 within 0.01 either way; landing seeds 0-7 mean ATE 1.01 -> 1.09 %, RPE max 0.0048 -> 0.0055 m/m, 0.0042
    -> 0.0025 deg/m. Without either prior (and with the refinement) landing's RPE rotation max was 0.0073 deg/m."""
    max_gyro_disagreement_deg: float = field(default=2.0, metadata={"min": 0.0, "max": 30.0, "step": 0.1, "unit": "deg"})
    """Before the IMU initialisation, a visual pose the gyro prior cannot be reconciled with (too few inliers after the
    gyro refinement) whose rotation is farther than this from the gyro's is treated as a tracking failure (the map
    coasts) instead of being kept (0: always kept, as before), degrees. The rotation error of uninitialised indoor maps
    was a median of 0.001-0.3 deg per MCI with spikes of 1-6 deg. Indoor E-I-C2 seeds 0-3: seed 1 RPE 0.0331 -> 0.0063
    m/m, 0.0156 -> 0.0052 deg/m; seed 2 5 -> 4 maps, tracked 75.6 -> 88.4 %, RPE 0.0470 -> 0.0324 m/m, 0.679 -> 0.296
    deg/m; seeds 0 and 3 unchanged. 1 deg cost seed 3 (RPE 0.0095 m/m, 0.023 deg/m); 3 deg helped seed 2 only. Applied
    to initialised maps too, it raised landing's (seeds 0-7) mean ATE from 3.71 to 3.77 %; as is, landing is unchanged."""
    ba_gyro_prior_uninit_deg: float = field(default=0.02, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "deg"})
    """Sigma of the gyro rotation priors between keyframes in the visual local BA before the IMU initialisation
    (0: ``gyro_prior_uninit_deg``; pose tracking keeps that one), degrees. The visual keyframe-to-keyframe rotation
    is what drifts (event-only: true relative rotations as 0.2 deg priors put all 24 landing seeds within 2 %).
    Landing E-I-C2, seeds 0-23: 0 (``gyro_prior_uninit_deg``, 0.2) mean ATE 4.53 % (median 1.07, worst 37.7, 18 of
    24 within 2 %; RPE above 0.01 m/m on 3 seeds, worst 0.0999); 0.05: 1.20 % (worst 8.2, 23/24); 0.02: 0.91 %
    (median 0.85, worst 1.97, 24/24; RPE at most 0.0073 m/m and 0.0022 deg/m on every seed); 0.01: 0.90 % (worst
    1.88, 24/24). The same 0.02 on pose tracking as well went to 0.98 % (worst 6.2), on pose tracking alone to 5.65 %.
    Indoors, where the scale is lost either way (see ``max_scale_std_ratio``), 0.02 splits the maps (seeds 0-3:
    1/1/4/1 -> 1/2/3/4 maps, tracked 88-99.5 % -> 78-99.5 %, mean ATE 19.3 -> 50 %, RPE within 0.01 m/m and deg/m
    on seed 0 only instead of 0, 1 and 3). Why: indoors the IMU initialisation is refused throughout ("scale
    estimate ... not positive"; without the prior one attempt at 1.4 s happens to pass), so maps coast and split at
    the event gaps. Ground-truth poses at the same keyframe times give 1.01 of the true scale; the prior's maps have
    better keyframe rotations (median error per pair 0.0026 vs 0.0039 deg, seed 1) but worse positions (similarity-
    aligned 0.30-0.37 m RMS over 1.5-1.9 m, against 0.08-0.11 m without it, and the map's scale drifting 4x within
    0.3 s). ``ba_gyro_prior_min_points`` limits it to well-observed keyframes. On the synthetic scene switch of
    ``tests/slam/test_configurations.py`` (the events resume on another scene) 0.02 lets PnP accept tracks carried
    across the switch (88 inliers where 0 finds 11 and bridges with the IMU): a wrong lock, ATE 2.7 -> 5.5 %. Those
    tracks sit on old-scene events inside MCIs that straddle the dropout, not on the gyro's KLT start (the gyro flow
    is 1-2 px there, and KLT from zero flow keeps the same 130 of 150 tracks); with
    ``EventWindowConfig.max_event_gap_ms`` 20 the switch is bridged with the prior too (ATE 0.81 %). Sensitivity
    (sigma +-5 %): landing keeps every seed within 0.01 m/m and deg/m at 0.019 / 0.02 / 0.021 (worst 0.0085 / 0.0073 /
    0.0091 m/m), while this option off with ``gyro_prior_uninit_deg`` at 0.19 / 0.2 / 0.21 leaves 4 / 3 / 5 landing
    seeds above 0.01 m/m. Indoors both are chaotic: seeds 0-3 mean ATE 15006 / 19.3 / 23.7 % (loose 0.19 / 0.2 /
    0.21; seed 0 alone 59954 / 15.1 / 17.2 %) and 51.1 / 50.3 / 30.2 % (0.019 / 0.02 / 0.021), 1-3 seeds within the RPE
    targets either way: the indoor figures of the default are one lucky draw of that spread. On by default (0.02)
    for the keyframe pairs ``ba_gyro_prior_min_points`` selects."""
    reanchor_before_init: bool = True
    """Take the rotations of the MCI poses relative to their keyframe from the gyro (zero bias) before the IMU
    initialisation too, not only after it (:func:`evpose.slam.gyro_prior.reanchor_rotations`); the initialisation
    re-anchors all of them with its bias estimate. Only maps the initialisation never reaches change: indoor E-I-C2
    seed 2 (five such maps) RPE 0.296 -> 0.124 deg/m, landing seeds 13 and 15 0.026/0.027 -> 0.014/0.016 deg/m;
    indoor seeds 0, 1, 3 and landing seeds 0-12, 14, 16-23 bit-identical."""
    klt_gyro_prediction: bool = True
    """Start the KLT tracking between MCIs where the gyro rotation moves each feature."""
    gyro_prior_deg: float = field(default=0.05, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "deg"})
    """Sigma of the gyro-integrated rotation between consecutive poses once the IMU is initialised (bias known), used as a prior by pose tracking (0 disables it), degrees."""
    ba_gyro_prior_min_points: int = field(default=0, metadata={"min": 0, "max": 200, "step": 1, "unit": "points"})
    """``ba_gyro_prior_uninit_deg`` applies only to keyframe pairs whose keyframes both observe at least this many map
    points; the others keep ``gyro_prior_uninit_deg`` (0: every pair), points. Indoor keyframes come every 4-6 ms
    and see a median of 3-11 points (landing: 77 ms, 31 points). E-I-C2 with that prior at 0.02, landing seeds 0-23 /
    indoor seeds 0-3 (without it: 4.53 % mean ATE, 3 landing seeds above 0.01 m/m / indoor 19.3 %, 1/1/4/1 maps):
    0 -> 0.91 %, none above / 50.3 %, 1/2/3/4 maps; 20 -> 0.91 %, none / 20.8 %, 1/3/3/1; 30 -> 0.88 %, none (RPE at
    most 0.0073 m/m, 0.0021 deg/m) / 16.9 %, seed 2 five maps (tracked 88 -> 76 %); 40 -> 1.07 % (21 of 24 within
    2 %), none (at most 0.0095 m/m, 0.0025 deg/m) / seeds 0, 1, 3 bit-identical to no prior, seed 2 ATE 25.1 -> 18.9 %
    but five maps, tracked 88 -> 76 %, 0.032 -> 0.048 m/m; 45 -> 2.11 %, seed 21 21.5 % and 0.0108 m/m / as without the
    prior (seed 2 0.124 -> 0.114 deg/m); 50 -> 2.19 %, seed 18 21.4 % and 0.0107 m/m / the same. 30 is the
    default (with ``EventWindowConfig.max_event_gap_ms`` 20, which the scene switch needs): every landing seed within
    the RPE targets and 2 % ATE; indoors seeds 0, 1 bit-identical, seed 3 ATE 19.0 -> 15.1 % (0.0058 m/m), seed 2 ATE
    25.1 -> 19.2 % but still off the RPE targets as before (0.048 m/m, 0.112 deg/m). Session 12 (``coast_s`` 0.4,
    ``rejoin_s`` 1.0; ``/tmp/s12/slamei/exp.py``: ``run_slam`` + ``atlas_metrics`` as bench ``landing_seed_spread``),
    30 -> 0, the default since: indoor E-I-C2 seeds 0-7 within both RPE targets 5 -> 8 of 8 (seeds 0 / 4 / 5 0.0191 /
    0.0252 / 0.0263 -> 0.0036 / 0.0015 / 0.0014 deg/m; seed 5's initialisation, refused on all 73 keyframes, was
    accepted at 1.24 s: ATE 754 -> 17.0 %, 0.218 -> 0.0061 m/m), mean ATE 111.2 -> 20.0 %. The rotation error came
    from the pairs under 30 points (indoors nearly all): under the loose prior the visual BA turned them by up to 5.8
    deg against the gyro (seed 0, two coasted keyframes 93 ms apart), and the full inertial BA after the
    initialisation left them so. Four neutral perturbations (``ba_huber_px`` 1.9 / 2.1,
    ``reprojection_threshold_px`` 2.4 / 2.6) x seeds 0-7: runs missing a target 15 -> 10 of 32 (rotation 12 -> 4,
    translation 6 -> 8; see ``carry_mci_scale``). Landing E-I-C2 seeds 0-7: mean ATE 1.16 -> 1.09 %, RPE at most
    0.0055 m/m and 0.0017 deg/m either way. Two of the rotation failures left (seed 6, 0.035 / 0.041 deg/m) are a
    homography decomposition 17 deg off the gyro re-joined into the map (the two-view maps' rotations were 1-24 deg
    off the gyro indoors, 0.6-2.7 deg on landing seeds 0-3); re-solving those more than 2 (0.5) deg off with the
    gyro's rotation, the translation from the epipolar constraints, refusing the map when that fails: indoor seeds
    4 and 6 (0 and 7) off the RPE targets, up to 17 (28) points of tracked time lost, landing at 0.5 deg 1.06 -> 1.04 %;
    at 5 deg (no landing map that far off) seed 6's two perturbed runs 0.041 / 0.035 -> 0.0077 / 0.0019 deg/m but its
    default run 0.0042 -> 0.0156 deg/m and seed 5 tracked 98.0 -> 83.4 %; keeping the first solution when the re-solve
    fails (2 deg) changed only seed 7 and fixed neither (not kept)."""
    gyro_prior_uninit_deg: float = field(default=0.2, metadata={"min": 0.0, "max": 5.0, "step": 0.01, "unit": "deg"})
    """The same prior before the IMU initialisation, with an unknown gyro bias, also used by the visual local BA (0 disables it): chained step after step, an uncorrected bias would bend the visual map, so it is looser or off, degrees."""
    ba_window: InertialWindowConfig = field(default_factory=InertialWindowConfig)
    """Scale anchors of the inertial local BA after the initialisation (:mod:`evpose.slam.inertial_window_config`)."""
