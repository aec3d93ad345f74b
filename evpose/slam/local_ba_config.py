"""Local bundle adjustment settings of the map-free SLAM's local mapping (:class:`LocalBundleAdjustmentSettings`).

One of the three groups :class:`evpose.slam.tracking_config.TrackingConfig` is made of; the fields keep their flat
names (``tracking.ba_window`` in a config file), and most carry the measurements that set them.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class LocalBundleAdjustmentSettings:
    """Which keyframes the local bundle adjustment optimises, its robust loss, priors and iterations."""

    ba_edge_along_sigma_px: float = field(default=0.0, metadata={"min": 0.0, "max": 50.0, "step": 0.5, "unit": "px"})
    """Event-only local BA: observations on a straight edge of their keyframe's MCI get this sigma along the edge (one
    pixel across it; 0: isotropic like every other observation), pixels. KLT on an edge measures only the motion across
    it and, started at zero flow, stays behind along it: a candidate source of the x-rotation bias of
    ``ba_rotation_rate_prior_deg_s``. About 40 % of the local BA's observations are on such edges (landing seed 2 and
    indoor seed 1 alike, 20-30 corner observations per keyframe). Session 13 (``/tmp/s13/slamedge/exp.py``, as
    ``ba_rotation_rate_prior_deg_s``; the four settings are the defaults and the neutral perturbations ``ba_huber_px``
    1.9 / 2.1 and ``reprojection_threshold_px`` 2.4), landing event-only, 3 -> seeds 0-11 mean ATE 2.52 -> 2.46 %
    (median 2.21 -> 1.66, within 2 % 5 -> 7), seeds 12-23 3.62 -> 2.07 % (3 -> 7 within 2 %; tracked at least 88.3 ->
    96.2 %); huber 1.9: 0-11 2.35 -> 2.67 % (6 -> 5), 12-23 3.65 -> 2.93 % (2 -> 7); reprojection 2.4: 0-11 2.67 -> 2.40
    % (6 -> 7), 12-23 2.25 -> 2.93 % (6 -> 2); over the 72 landing runs 2.85 -> 2.58 %, paired -0.27 +- 0.24 (s.e.)
    points (better in 41, worse in 31), within 2 % 28 -> 35, tracked at least 84.0 -> 95.7 %; the summed
    keyframe-to-keyframe x-rotation error (median over seeds 0-11, defaults) 8.6 -> 5.7 deg. Indoor event-only seeds 0-3
    with the defaults 6.84 -> 9.83 % (tracked 80.2 -> 76.1 %), huber 1.9 11.38 -> 7.83 (76.5 -> 80.4), huber 2.1 10.11
    -> 10.16 (84.1 -> 75.6), reprojection 2.4 9.38 -> 13.84 (76.1 -> 82.5); seeds 4-7 10.80 -> 12.09 (82.5 -> 90.9):
    over the 20 runs 9.70 -> 10.75 %, paired +1.05 +- 1.06 points, tracked 79.9 -> 81.1 %. Off: the landing gain is
    about one standard error and the indoor seeds 0-3 got worse with the defaults. Landing seeds 0-11 with the defaults:
    2 -> 2.44 % (6 within 2 %; indoor 0-3 10.52 %), 10 -> 2.73 (7), 30 -> 3.31 (5); 3 only in maps with more than
    ``local_window`` keyframes -> 2.62 (5; indoor 0-3 9.35); 3 with the tensor over KLT's 23 px window -> 2.74 (5;
    indoor 9.98). Session 19 (``/tmp/s19/turn9/edge_pnp.py``, removed): every MCI's PnP pose re-solved by Gauss-Newton
    with the same along-edge sigma from the current MCI's structure tensor: landing seeds 0-23 (defaults 1.82 %, 19
    within 2 %) 3 -> 2.66 % (15; seed 3 15.5 %), 1.5 -> 2.39 % (16), paired +0.84 +- 0.63 / +0.57 +- 0.37; the summed
    keyframe x-rotation error fell (mean 7.0 -> 5.3 deg) but the RMS keyframe rotation error rose (1.40 -> 1.54 deg).
    Event-inertial runs never use it, pixels. Session 22 (lead, ``/tmp/s22/birth/``): a loose sigma
    along each old point's image motion at birth instead (the direction between its first two keyframe observations;
    its observations from the 3rd / 5th / 8th keyframe on; the turn9 study in :mod:`evpose.slam.features` found the
    tracks that live through the landing's turn off mostly along their birth flow), landing seeds 0-23 against the
    defaults' 1.80 % (20 within 2 %): 3 px from the 3rd 2.45 % (11; paired +0.65 +- 0.23 points, 5 better), 3 px from
    the 5th 2.21 % (16; +0.42 +- 0.34), 1.5 px from the 5th 2.43 % (14; +0.63 +- 0.36), 2 px from the 8th 2.07 % (17;
    +0.27 +- 0.23), so not kept (code in commit eabb109, reverted)."""
    ba_edge_max_ratio: float = field(default=0.1, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """An observation is on a straight edge when the smaller eigenvalue of the MCI's structure tensor (11 px square)
    there is below this share of the larger, ratio. With ``ba_edge_along_sigma_px`` 3, 0.05 -> landing event-only seeds
    0-11 mean ATE 2.51 % (median 1.82, 9 within 2 %, but seed 7 11.20 %, tracked 88.9 %), indoor seeds 0-3 9.29 %."""
    local_window: int = field(default=6, metadata={"min": 2, "max": 30, "step": 1, "unit": "keyframes"})
    """Keyframes optimised by local bundle adjustment, keyframes. Session 11, landing event-only seeds 0-11, 60 runs
    (defaults and four perturbations, see ``MciConfig.reference_fraction``, 0.5 there): 10 -> mean ATE 2.60 -> 2.30 %,
    within 2 % 30 -> 35 of 60, paired -0.30 +- 0.19 points (32 runs better, 28 worse), tracked at least 95.0 % (88.5);
    short of the evidence for a default, keyframes."""
    ba_window: int = field(default=10, metadata={"min": 0, "max": 30, "step": 1, "unit": "keyframes"})
    """Keyframes the event-only visual local BA optimises (0: ``local_window``), keyframes. Unlike ``local_window`` it
    leaves the keyframes the projection search reads alone, so only keyframe MCIs pay for it; event-inertial runs keep
    ``local_window``. Why (session 18, ``/tmp/s18/landfail9/``, landing event-only 3 s): the runs over 2 % are neither
    bad two-view maps (their translation direction is 20-70 deg off on passing and failing seeds alike) nor map switches
    (one map on 47 of 48 seeds), but a runaway of the pose chain along the rotation-translation valley of the sideways
    flight over near-planar ground. After the sparse stretch of the turn (2.0-2.3 s, 14-21 PnP inliers) each new
    keyframe's PnP pose turns a further 3-6 deg about the camera x axis, its step shrinks to 0.3-0.5 of the true one and
    tilts 50-100 deg towards the optical axis (seeds 2, 9, 13, 24, 31; seeds 27 and 36 about y in the first leg). The
    PnP poses carry a +x bias on every seed (summed over a run's keyframe steps 13-30 deg); on passing seeds later BAs
    take it out (seed 7: 14 -> 2 deg), on failing ones a six-keyframe BA keeps it (seeds 2, 9, 13: 17-27 -> 23-27 deg).
    Ten keyframes reach back past the turn. 6 (``local_window``) -> 10: seeds 0-23 2.07 -> 1.82 % (within 2 %: 15 -> 19),
    held-out seeds 24-47 2.88 -> 2.86 % (13 -> 14, median 1.96 -> 1.77); with ``ba_huber_px`` 1.9 2.86 -> 2.36 % (12 ->
    13), 2.1 2.11 -> 2.06 % (14 -> 16); held-out with huber 1.9 2.62 -> 2.58 % (14 -> 14), 2.1 2.28 -> 2.17 % (13 ->
    12). The 144 runs 2.47 -> 2.31 % (median 1.91 -> 1.76, within 2 % 81 -> 88), paired -0.16 +- 0.10 points, better
    in 83, worse in 61; seeds 0-23 alone (72 runs) -0.26 +- 0.18, the held-out 72 -0.06 +- 0.11 (40 -> 40 within 2 %):
    a small gain; a second held-out set simulated for the lead's check, seeds 48-71 (defaults): 2.68 -> 2.51 % (median
    2.05 -> 1.89 %, within 2 % 12 -> 13), paired -0.18 +- 0.21, better in 14, worse in 10, so 10 is the default.
    The collapses of seeds 2, 9, 13 went, seed 10's came (1.36 -> 4.58 %). Indoor seeds 0-7 7.04 -> 6.83
    % (tracked from the events 45.3 -> 40.7 %), held-out 8-11 8.59 -> 7.98 % (40.3 -> 44.3 %), ``ba_huber_px`` 1.9 8.21
    -> 8.14 % (41.2 -> 42.1 %). E-I-C2 bit-identical. CPU (landing seeds
    0-3 twice, alternated in one process): median per MCI 27.0 -> 26.9 ms, mean 30.0 -> 32.8 ms, a keyframe MCI's
    tracking +6.9 ms. Other windows, seeds 0-23 / 24-47: 8 -> 1.78 / 2.69 % (19 / 15 within 2 %); 12 -> 1.66 / 2.43 %
    (21 / 17), the 144 landing runs as above 2.26 % (102 within 2 %, paired -0.21 +- 0.11; held-out 72 -0.13 +- 0.12,
    40 -> 45 within 2 %), but indoor seeds 0-7 8.41 %, 8-11 7.27 %, huber 1.9 8.96 % with a run tracked 78.8 % (20
    runs +0.58 points against 10's -0.23); 15 -> seeds 0-23 1.98 % (19, seed 19 8.00 %); 15 cut to the keyframes at
    most 0.6 s older than the newest, at least 6: 2.19 % (13): the span in time of the ordinary window, not the dense
    keyframes of the turn, is what matters. Session 20 (``/tmp/s20/post9/``: ``diag.py``, ``ana2.py``, ``ana3.py``;
    defaults on all 72 landing seeds 2.40 %, 46 within 2 %), where the runs over 2 % after the turn (seeds 10, 24, 31,
    32, 37, 38, 65, 71) lose it. Keyframe poses aligned on the first leg (rotation from the orientations, then scale and
    shift): the rotation error about the camera x axis is +3.5 to +7 deg at 2.0 s on passing and failing seeds alike;
    on failing seeds it grows to +39 / +49 deg by 2.9 s (seeds 10, 31) while 0.2 s of keyframe steps shrink to 0.3-0.4
    of the first leg's scale; passing seeds stay below +9 deg and at 0.9-1.25 after 2.2 s (seeds 2, 5). The rotation enters
    through the per-MCI PnP: the online rotation increments about x between consecutive MCIs after 2.2 s sum to +6.7 to
    +29 deg over the PnP steps of the failing seeds (+0.7 to +7 deg on passing seeds 0, 1, 2, 5, 7, 16); the keyframe
    insertions' BA takes it back out on passing seeds (their keyframe steps sum to -4.4 to +3.5 deg) and not on failing
    ones (+4 to +18.5 deg; seeds 65 and 71 -2.6 / -7.9 deg against PnP steps of +15 / +13). Failing runs track a little
    fewer map points after the turn (27-28 against 31-33 per MCI, of 87-101 tracks) and insert about 20 % more
    keyframes; PnP outliers 3-14 % alike. Two views hold no usable check of a keyframe's rotation: keyframe pairs share
    48 tracks one keyframe apart and 28 five apart, and the rotation of an essential matrix of them is 5-15 deg RMS off
    about x (a homography, decomposition nearest the estimate: 2.4 deg one keyframe apart, 4.7 deg and more beyond)
    against the SLAM's own 2.1 deg (seeds 2, 10, 31, 37, ``eprobe.py`` / ``hprobe.py``). Which seeds run away is
    chance: over five variants (the defaults, three re-anchorings of :mod:`evpose.slam.keyframe_search`, and PnP's LM
    started from the motion model in :func:`evpose.slam.tracking.estimate_pose`; each 2.40-2.66 %) a seed outside the
    first-leg collapses (27, 36, 60, 67) runs over 2 % in 0 / 1 / 2 / 3 / 4 / 5 of them for 16 / 20 / 17 / 9 / 6 / 0
    seeds, against 10.7 / 24.0 / 21.4 / 9.6 / 2.1 / 0.2 for independent draws at the mean rate 0.31: mostly chance,
    with some seeds (4, 21, 38, 45, 52, 71) failing in four of five. Every variant mended most of the defaults'
    runaways and sent a like number of other seeds away. Oracles (``pnporacle.py``, ``baoracle.py``, ``both_oracle.py``;
    seeds 10, 31, 32, 37, 38 at 4.58 / 4.56 / 4.03 / 4.65 / 3.81 %), from 2.2 s on: each MCI's PnP pose replaced by
    the newest keyframe's pose and the true motion since it -> 2.90 / 2.11 / 1.69 / 5.27 / 1.29 %, its rotation only
    -> 2.31 / 2.49 / 1.50 / 4.67 / 3.01 %; the true keyframe-to-keyframe rotations as 0.2 deg BA priors -> 2.19 / 3.08 /
    1.22 / 4.80 / 1.25 %; both -> 2.19 / 2.21 / 1.04 / - / 1.06 % (seed 37 loses its map anyway). From 1.5 s the BA
    priors alone bring seeds 10 / 31 to 1.83 / 1.09 %, so the damage starts in the turn; at 0.5 deg they give 1.81 /
    2.00 / 1.40 / 3.33 % (seeds 10, 31, 32, 38) and at 1 deg 2.47 / 4.74 / 1.64 / 3.19 %: the keyframe observations
    pull against a true rotation held to 1 deg, so it is the data, not a flat cost, that turns the chain. Why the turn:
    event-image corners are not fixed scene points. Tracks 3-12 MCIs old within 1.5-2.4 s (seeds 10 / 2, error against
    the ray-cast of their birth pixel, ``te_turn.py``) are off by a median 1.27 / 0.92 px when the image motion turned
    by under 15 deg since their birth, 1.79 / 1.78 px at 15-40 deg and 2.85 / 2.44 px beyond 40 deg (in the legs 0.90 /
    0.92, 0.98 / 1.15 and 1.48 / 1.53 px): what KLT follows slides with the motion's direction, alike for every track of
    the turn. Ending a track's tie to its map point once its own MCI-to-MCI steps turned by over 35 / 60 deg since its
    first step (``dircut.py``; seeds 10, 31, 32, 38, 2, 0, 5, 7 at 2.88 %): 4.54 / 3.47 % (the sparse turn starves
    into coasting; at 60 deg seed 2 lost its map). Giving BA observations a sigma of 1 px plus 1 px per 30 deg the
    keyframes' image motion turned since the point's first keyframe, at most 3 px (``dirsig.py`` with
    ``/tmp/s20/post9/obs_sigmas.patch``): those eight seeds 2.71 % (10, 31, 32: 2.83 / 2.15 / 2.16 %;
    2, 38: 4.03 / 4.74 %), within 2 % 4 -> 2, RPE higher on six of them. Session 22 (``/tmp/s22/lead9/``, figures in
    :mod:`evpose.slam.features`): the slide is no lead or lag of the corners along the image flow (against true
    corners -0.26 to +0.20 px), and removing each track's error along the true flow leaves the drift (seeds 0-23 1.80
    -> 2.42 %) while removing it across the flow mends the four failing seeds (1.65 %, 22 of 24 within 2 %), in the
    turn's MCIs alone (1.1-2.2 s) 1.49 %, 19 of 24 better."""
    ba_fixed_keyframes: int = field(default=1, metadata={"min": 1, "max": 5, "step": 1, "unit": "keyframes"})
    """Event-only local BA holds this many of the window's oldest keyframes fixed once the map has more keyframes than
    the window (before that, only the first keyframe and ``ba_scale_anchor``); with two or more the fixed poses also
    set the window's scale, and the range factor of ``ba_scale_anchor`` is not added. Event-inertial maps keep one.
    Simulated landing, event-only, 3 s, seeds 0-23 (session 8 recordings; the default then measured mean ATE 3.01 %,
    median 2.52, worst 5.88, 10 seeds within 2 %): 2 -> mean 2.85 %, median 2.44, worst 5.25, but 4 within 2 %
    (12 seeds better, 12 worse); indoor seeds 0-3 8.76 -> 8.57 % at the same tracked time (49-54 %). With
    ``local_window`` 8 (seeds 0-4, 8-15 only): 2.47 % against 3.19 % (CPU 31.9 against ~25 ms per MCI); 3 fixed of 8:
    2.62 %. Single changes re-draw every seed's outcome by +-1-2 points here (dropping single observations over 2.5 px
    instead of whole points: 2.62 %, 8 within 2 %), so none of these is a default. Session 38 (``/tmp/s38/lm38``,
    figures as at ``TrackingConfig.min_triangulation_deg``; paired against main fd512ff's defaults, tag ``fin``): 2 ->
    landing 0-23 1.474 -> 1.258 % (-0.216 +- 0.222, 13 better, 11 worse; within 2 % 21 -> 22: seeds 4 / 12 / 17 6.13 /
    2.45 / 2.58 -> 1.30 / 2.41 / 1.49, seed 8 1.50 -> 3.02, the other 21 +0.037), held-out 24-35 1.286 -> 1.286 %
    (-0.001 +- 0.143, 6 / 6, within 2 % 10 -> 12), indoor 0-39 1.901 -> 1.902 % (only seeds 5 and 36 differ, by 0.005
    points: the rooms' maps rarely outgrow the window); the landing map's spread over 1.95-2.25 s (log chord sd 0.18 /
    0.18 / 0.15) is no smaller (0.23 / 0.20 / 0.12), keyframes."""
    ba_velocity_prior: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "ratio"})
    """Event-only local BA: sigma of a constant-velocity factor per three consecutive keyframes, as a share of their
    speed (:mod:`evpose.slam.motion_prior`; 0 disables), ratio. Landing event-only seeds 0-23: 0.2 -> mean ATE 2.75 %
    (median 2.52, worst 7.21, 4 within 2 %) against 3.01 % (2.52, 5.88, 10); the scale drift it targets fell on some
    seeds (seed 9: 0.5 s pieces 258 -> 28 % apart, ATE 5.37 -> 1.77 %) and the outcome of others swung the other way.
    Seeds 0-4, 8-15: 0.1 -> 2.96 %, 0.4 -> 3.03 %, 0.2 with ``ba_fixed_keyframes`` 2 -> 3.48 % (base 3.19). Session 18
    (seeds 0-23, defaults then 2.07 %, 15 within 2 %): 0.3 -> 2.40 % (13), paired +0.32 +- 0.38. Session 27
    (``/tmp/s27/turn27``; the indoor maps that cross a turn drift in scale, module notes of
    :mod:`evpose.slam.event_coasting`), indoor event-only seeds 0-7 (defaults 6.84 %; under the defaults and the four
    neutral perturbations 7.63 %): 0.1 / 0.2 -> 9.04 / 10.00 % (paired +2.19 +- 1.74 / +3.16 +- 1.17); 0.2 with MCIs
    warped by the true motion in the turns 9.25 -> 8.34 %. Off."""
    cull_min_depth_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "ratio"})
    """Event-only maps: after each local BA a point that lies nearer a keyframe observing it than this share of that
    keyframe's median point depth is culled (:func:`evpose.slam.local_map.cull_points`; 0: off), ratio. Session 40
    (``/tmp/s40/eo40``: ``whyba.py`` finds the BAs whose LM took no step, ``tridiag.py`` the depths triangulation
    accepts; truth offline only): a track at the epipole of its keyframe pair (the camera closing on the scene: the
    rooms' last stretch, the landing's descent) holds nothing of its point's place along the baseline, and the BA slid
    such points into a keyframe's camera centre (indoor seed 5's point 202 at 3e-5 of its keyframe's median depth 0.24,
    landing seed 17's point 284 at 9e-5 of 0.74). There its Jacobian (8e6 against 1e4 for the others) makes the normal
    equations singular: LM tried every lambda without a step and left the map as it was, silently, while the point
    stayed in the window (indoor 5: the 7 BAs of 2.72-2.93 s; landing 17: the 5 BAs of 2.50-2.84 s, after which its
    keyframe steps fell to 0.4 of the truth). Triangulation accepts no point nearer than 0.07 of the median (indoor 0-2,
    5, 21, 52: 837 points, 0.1 % quantile 0.12; landing 0, 1, 12, 17: 1627 points, minimum 0.29), so 0.01 culls only
    collapsed ones. 0.01 against main 8b52aca's defaults (tag ``ds10``, ``run.py`` / ``batch.sh`` / ``cnt.py`` = ``evpose
    slam`` + ``evpose eval --atlas --correct-scale``): indoor 0-53 1.825 -> 1.875 % (paired +0.050 +- 0.049, 5 better, 3
    worse; within both targets 44 -> 43: seed 5 4.38 -> 6.96, 8 1.96 -> 2.51, 15 1.62 -> 1.36, 41 1.71 -> 1.59), fresh
    54-61 unchanged, landing 0-23 1.470 -> 1.463 % (-0.007 +- 0.020; seed 17 2.58 -> 2.17, 3 1.08 -> 1.31), 24-35
    unchanged. Off: once its BA runs, seed 5's map shrinks in the BA itself (its keyframe steps' log scale hand-on summed
    -3.76 after the BAs against -1.05 at PnP), which the stalled BA had spared. Four runs keep a stalled BA, all at a
    young map's second or third keyframe (indoor 11, 18, 40, landing 1): another cause."""
    ba_rotation_rate_prior_deg_s: float = field(default=0.0, metadata={"min": 0.0, "max": 200.0, "step": 1.0, "unit": "deg/s"})
    """Event-only local BA: sigma of a constant-rotation-rate factor per three consecutive keyframes, the change of the
    body-frame rate between the two keyframe steps (:func:`evpose.slam.motion_prior.add_rotation_rate_factors`; Huber
    at two sigmas; 0 disables), degrees per second. Session 12, landing event-only seeds 0-11 (defaults: mean ATE
    2.53 %, median 2.21, worst 5.59, 5 within 2 %; 60 runs with the four neutral perturbations of
    ``MciConfig.reference_fraction``: 2.62 %, median 2.09, 27 of 60 within 2 %, RMS keyframe-to-keyframe rotation
    error 1.82 deg): 40 -> defaults 2.27 % (median 1.73, 7 within 2 %; the corner collapse of seed 1, 4.63 -> 2.76 %,
    gone), 60 runs 2.49 % (26 within 2 %), paired -0.12 +- 0.19 points (better in 34 of 60), rotation error 1.71 deg;
    with ``ba_velocity_prior`` 0.2 as well: 2.46 % (30 of 60), paired -0.16 +- 0.21, rotation error 1.30 deg. Seeds
    0-3 only: 20 / 40 / 60 -> 2.35 / 1.79 / 2.87 % (defaults 2.84). The per-step rotation error fell by up to a third
    and the ATE did not follow: what drives the ATE is the map's scale drift (0.5 s pieces of one map need scales
    10-30 % apart on most seeds, up to 2x after a collapse; ATE and that spread move together), not the per-step
    jitter. The drift is a bias, not noise: the keyframe-to-keyframe rotation errors about the camera x axis sum to
    +6.5 to +8.7 deg over the 30 keyframes of seeds 2, 5, 10 (0.2-0.3 deg per step, the axis coupled with the
    dominant sideways translation over the near-planar ground; at 5 m depth that re-scales a 0.25 m keyframe step by
    about 10 %), and the map's own depth scale per keyframe (rendered true depths, seed 3) stays within +-10 % while
    the trajectory's 0.5 s scales drift 0.83-1.13 of their mean. New points are not its source: placing every new point
    at its rendered true depth (scaled to the map) left the x sums at 7.3 / 8.9 / 9.1 deg (seeds 2, 3, 10; ATE 2.66 /
    3.06 / 2.33 -> 2.45 / 2.01 / 2.42 %), though it removed seed 1's corner collapse (4.63 -> 1.52 %). Neither is the
    estimator: a full BA of a run's final map started at the true keyframe poses (points re-triangulated from them)
    ends at the same x sums, 6.75 / 9.88 / 8.29 deg (seeds 2, 10, 5; the runs' own 6.53 / 8.69 / 8.48), and 6.44 /
    7.37 / 6.15 with only the points seen by three or more keyframes: the keyframe observations themselves carry the
    bias, so priors and windows of the BA cannot remove it. Session 14 revises that (oracles replacing every live track
    after KLT, ``/tmp/s14/eobias/oracle2.py``; each track's world point ray-cast from its first position; seeds 0-11,
    defaults 2.52 %, x sums median 8.6 deg): true projections 0.52 % (12 of 12 within 2 %, x median 0.4 deg); true
    projections plus each MCI's affine fit of the real track errors (what a wrong MCI time, warp or intrinsics moves)
    0.69 % (12, 0.5 deg); the real errors minus that fit 2.90 % (4, 4.7 deg): per-track errors drive the drift, not the
    MCIs. Zero-mean white noise on the true projections reproduces it: 1 px per MCI and axis 2.02 % (7; five runs turned
    20-47 deg about x), 0.5 px 0.99 % (11), a 0.3 px-per-MCI random walk 1.48 % (10). Unbiased observations thus leave
    the estimate biased along the rotation-translation valley, its sign set by the flight: in the turn into the second
    leg (1.5-2.5 s, sideways along -y) the keyframe translation tilts toward the optical axis, may flip (seed 3, 1 px:
    123 deg off at 2.49 s), its length falls from 0.19 to 0.04-0.09 map units per true metre and the x rotation takes
    2-6 deg per keyframe. Snapping to the truth only observations off by more than 1.5 px: 1.14 % (11); only tracks born
    within 4 px of a depth step: 1.48 % (9). Under the 1 px oracle, ``ba_iterations`` 0 gave 7.6-10.8 % (seeds 0-2,
    43-63 deg about y), 30 iterations 9.5 / 33.8 deg (seeds 0, 1; 10: -0.2 / 3.9), no parallax gates 20-40 deg (seeds
    0-3), ``min_triangulation_deg`` 2 1.54 % (seeds 0-5; 2.09). On real tracks: ``min_triangulation_deg`` 2 3.23 % (2 of
    12), ``min_pair_parallax_deg`` 3 2.83 % (5), ``ba_velocity_prior`` 0.2 2.72 % (6), that pair gate at 1 deg for
    keyframes seeing fewer than 40 map points 2.45 % (5; 6 seeds better, 6 worse), the PnP pose re-solved with each
    point's sigma grown by the projection error its depth uncertainty allows (its keyframes' parallax against the
    current view) at gain 1 / 2: 2.77 / 2.57 % (5 each); all removed. The lever left is track precision. This
    factor's constant-rate prediction as a 0.5 deg prior of every MCI's pose (PnP refined like the gyro prior) was worse: 54
    runs +0.24 +- 0.22 points (21 of 54 within 2 %); with the BA factor at 40: defaults 2.75 %. Both factors with
    ``min_observations`` 3 and ``keyframe_displacement_px`` 14: 25 runs -0.09 +- 0.26 (rotation error 0.99 deg).
    Starting each MCI's pose estimate at the last pose's rotation (translation still extrapolated), in case the
    extrapolated rotation rate carried the bias from step to step along the weakly observed direction: seeds 1, 2, 3,
    10 4.63 / 2.66 / 3.06 / 2.33 -> 2.07 / 1.62 / 1.47 / 2.91 %, but over the 60 runs +0.05 +- 0.15 points (29 of 60
    within 2 %). Session 18 (seeds 0-23, defaults then 2.07 %, 15 within 2 %): 20 -> 2.45 % (15; seeds 2 and 13
    out of their collapse, seed 9 into two maps), 10 -> 2.32 % (16). Session 29 (``/tmp/s29/scale29``, ``run.sh`` /
    ``cmpj.py``; the indoor legs' keyframe steps trade rotation for translation, :mod:`evpose.slam.local_map`), indoor
    event-only seeds 0-7 (defaults 3.730 %): 20 / 40 / 80 -> 4.626 / 3.903 / 3.049 % (paired +0.90 +- 0.81 / +0.17 +-
    0.81 / -0.68 +- 0.99; 3 better and 5 worse each; at 80 seed 4 9.81 -> 2.55 % by other maps, seed 0 4.24 -> 4.34 %);
    80 under the defaults and the four neutral perturbations (40 runs) 3.153 -> 3.177 % (+0.02 +- 0.30, 19 better, 21
    worse; segment metric 2.62 -> 2.98 %). Off, degrees per second."""
    ba_room_prior_deg: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "deg"})
    """Event-only local BA: each free keyframe's rotation held to the map's room frame by the camera-from-room rotation
    measured from its MCI's straight edges along the room's three axes, at that measurement's own covariance plus this
    sigma, over ``ba_room_prior_gain`` (:mod:`evpose.slam.room_axes`, Huber at two sigmas; 0 disables), degrees.
    Session 30 (figures and scripts in the module notes), against the defaults (indoor event-only seeds 0-7 3.942 %, 40
    pooled runs 3.294 %, 8-19 3.566 %; landing event-only 0-23 1.317 %): 0.2 at gain 1: 0-7 2.704 % (paired -1.24 +-
    0.91, 6 better), pooled 2.743 % (-0.55 +- 0.23, 29 better), 8-19 3.544 % (-0.02 +- 0.32, 6 better, 6 worse),
    landing 1.460 % (+0.14 +- 0.12, 22 of 24 within 2 %); 0.1 at gain 4: 0-7 2.745 % (-1.20 +- 1.10), pooled 2.732 %
    (-0.56 +- 0.29, least tracked 79.6 %), 8-19 pooled over the same five settings 3.695 -> 3.436 % (-0.26 +- 0.24, 35 of
    60 better), landing 1.911 % (+0.59 +- 0.19, 17 of 24 within 2 %). Off: the indoor gain is within the noise beyond
    seeds 0-7 and the landing gets worse. Session 31 (``/tmp/s31/room31``, module notes): the landing's measurements
    were wrong (a camera looking straight down; median 13-16 deg off); dropping those whose three axes explain under
    90 % of the MCI's straight-edge length (``RoomAxesSettings.min_axis_share`` 0.9, now its default) leaves the landing
    without priors: 0.1 at gain 4, landing 0-23 bit-identical to the defaults (1.317 %), 48-71 too (1.806 %), 24-47 1.626 -> 1.621 % (priors on
    seeds 28 / 36 only: 1.68 / 3.37 -> 1.50 / 3.42 %; 20 within 2 % either way); indoor 0-7 3.026 %
    (-0.92 +- 1.12), pooled 40 runs 2.989 % (-0.31 +- 0.31, 28 better), 8-19 2.965 % (-0.60 +- 0.51, 8 better), 8-19
    pooled 60 runs 3.695 -> 3.370 % (-0.33 +- 0.22, 36 better), all 100 indoor runs -0.32 +- 0.18 (64 better), the 0.5 s
    segment metric level; but seed 3 79.6 % tracked (defaults 89.2 %) and 20-30 % more CPU indoors. Session 32
    (``/tmp/s32/room32``, module notes): indoor 0-19 3.773 -> 3.029 % (-0.74 +- 0.53, 13 of 20 better), seed 3 still
    79.6 % (one MCI's timing before a blank wall; the defaults' 89.2 % holds a three-pose map across it), CPU 1.10x
    the defaults' (1.27x before the yaw search ran its candidates at once). Still off: seed 3's tracked share."""
    ba_room_prior_gain: float = field(default=4.0, metadata={"min": 0.1, "max": 100.0, "step": 0.1, "unit": "ratio"})
    """``ba_room_prior_deg``: the prior's rotation information is the measurement's (plus the sigma floor) times this: in
    situ the measurements' estimated sigmas ran at about three times their errors (:mod:`evpose.slam.room_axes`), ratio."""
    ba_iterations: int = field(default=10, metadata={"min": 0, "max": 100, "step": 1, "unit": "iterations"})
    """Levenberg-Marquardt iterations of local BA (0 disables it), iterations. Session 18, landing event-only seeds 0-23
    (2.07 %, 15 within 2 %): 25 -> 2.20 % (17), tracked at least 88.3 %. Session 29 (``/tmp/s29/jit29``, ``run.sh``,
    ``cmpj.py``; with ``refit_tracked_poses``): 20 -> indoor event-only seeds 0-7 3.730 -> 2.828 % (paired -0.90 +-
    0.95, 3 better, 5 worse: seeds 0 / 4 / 6 4.24 / 9.81 / 3.44 -> 2.44 / 2.77 / 2.22, seeds 1 / 2 / 5 2.74 / 2.68 /
    1.48 -> 3.78 / 3.67 / 2.22); under the defaults and the four neutral perturbations (40 runs) 3.153 -> 3.198 % (+0.05
    +- 0.27, 18 better, 22 worse; segment metric 2.62 -> 2.98 %): within the spread."""
    ba_huber_px: float = field(default=2.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Huber threshold of the reprojection factors, pixels. Session 14, landing event-only seeds 0-11 (defaults 2.52 %,
    5 within 2 %): 1.0 -> 2.51 % (5; seeds 1, 3, 4, 10 better, seed 7 7.16 % in two maps, 8 3.70 %). Session 22
    (``/tmp/s22/turn9``, removed: commit d6c2af7): a keyframe made from an MCI with ``r`` < 1 times the last 20 MCIs'
    median event count observed with sigma ``min(r ** -p, 3)`` px: landing seeds 0-23 (1.80 %, 20 within 2 %) p 0.5 /
    1.0 -> 1.85 / 2.40 % (19 / 11; paired +0.05 +- 0.18 / +0.60 +- 0.36)."""
    ba_scale_anchor: float = field(default=0.02, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "ratio"})
    """Event-only local BA holds the distance between the window's two oldest keyframes at its value before the
    optimisation, with this sigma as a share of that distance (0 disables), ratio. With one fixed keyframe the monocular
    scale is a gauge freedom of the BA, and the solver slid along it: on the simulated landing seed 9 the median depth
    of the map points fell from 0.60 to 0.05 map units within four keyframes (altitude: 6.4 to 6.1 m), and such
    collapses ended in 16-20 % ATE and a lost map. Over seeds 0-23 (event-only, 3 s) 0.02 lowered the scale-aligned ATE
    from a mean of 5.0 % (median 3.0, worst 20.6) to 3.2 % (median 2.7, worst 9.3), better on 14 seeds and worse on 9;
    0.01 gave 3.5 % (median 3.1), 0.05 3.6 % (median 3.0); fixing the second keyframe outright 3.7 % on seeds 0-15.
    The subset 0-7 alone got slightly worse (mean 3.7 -> 3.8 %, median 2.7 -> 3.1, but no run split into two maps), and
    indoor seeds 0-3 (maps of a few keyframes) went from 13.0 % to 14.1 % mean ATE at the same tracked time (45-54 %).
    Not applied in event-inertial mode: on landing seeds 0-7 E-I-C2 it raised the mean ATE from 3.7 % to 5.9 %."""
