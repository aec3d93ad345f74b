"""Local mapping: keyframe decision and insertion, triangulation of new points, point culling.

Feature associations come from KLT tracks (one track id per key point), not
descriptors, so a map point is tied to the track that created it.

Where the indoor rooms' maps lose their scale (session 28, ``/tmp/s28/scale28``; simulated indoor room, event-only, 3 s
at 346x260; ``diag.py`` hooks every keyframe insertion and records the map's depth scale d = median(estimated depth /
ray-cast true depth) of the points a keyframe sees: of the old points at the inserted pose, of the points triangulated at
it, and of every window keyframe before and after the local BA; ``ana*.py`` sum it up; ``exp40.py`` is the harness with
a map-count-neutral metric: each run's trajectory cut into 0.5 s pieces of ground-truth time, each map's part of a piece
Sim(3)-aligned on its own, mean RMS / travelled distance, "seg" below; ``cmp.py`` pairs two run sets). Indoor seeds 0-3:

- The turn (0.85-1.9 s) is coasted, not tracked: its maps hold 101 / 88 / 96 / 109 coasted keyframes against 5 / 6 / 0
  / 3 placed by PnP, and every coasted MCI is a keyframe that triangulates. A coast moves the camera at its held
  velocity, which in maps born in the turn (a two-view map over millimetres) is 3-37 times too fast for the map's
  depths (0.25 s pieces: trajectory scale 5.0-15.3 map units per metre against a depth scale of 0.23-0.7; seed 2's map
  2: 13.4 against 0.4). The points triangulated at those poses carry the coast's scale, not the map's: their depth
  scale wanders 0.16-2.5 from keyframe to keyframe (seed 0, 1.0-1.56 s), seed 3's map jumped from 0.41 to 6.9 within
  0.25 s, and PnP, once it resumes on those points, moves the trajectory to their scale (seed 3: 5.3 -> 15.3).
- Visually tracked maps (the legs, 95 % PnP) shrink: new points come out nearer than the old points of the same
  keyframe, mean log ratio -0.117 (1476 points, seeds 0-5), -0.18 for pairs of 2-3 deg baseline over depth and -0.06
  beyond 8 deg, the BA keeps it, and the depth scale falls 0.44 -> 0.26 (seed 0) and 0.51 -> 0.23 (seed 3) over the
  second leg's second; the keyframe steps follow the depths (step length / depth scale 0.7-1.5) but point 5-60 deg off
  the true direction.
- The local BA rescales young maps (fewer keyframes than the window): window depth scale +12 to +67 % in one BA on
  seeds 1, 2, 3; in mature windows it moves 3-10 %.
- The 0.5 s pieces (seeds 0-5, ``ana9.py``): RMS / distance 4.2 % where coasted (17 pieces), 8.3 % where tracked (13;
  the two 0.25 s halves aligned on their own still 5.1 %, pose-to-pose jitter 3.9 %): per-piece error, not the drift
  between pieces, is most of the indoor ATE, and seg tracks the ATE (defaults 8.14 % against 7.63 %).

Oracles (``oracle_hook.py`` with ``exp40.py``, ``ORACLE=...``; new points moved along their ray to the ray-cast true depth
times the map's depth scale at that keyframe), indoor seeds 0-7 defaults (6.84 %, seg 7.70 %, 30 maps, from the events
40.8 %): at keyframes placed by PnP 8.05 % (paired +1.21 +- 1.12, seg 8.61); at coasted keyframes 5.18 % (-1.66 +- 0.65,
7 of 8 better; seg 5.23, -2.47 +- 1.16; 38 maps, 33.3 %); at both 6.79 %. So the scale a room's map loses goes into the
points the coasts triangulate; the new points of tracked keyframes are no lever (as on the landing, session 12).
:attr:`TrackingConfig.coast_depth_level` is the non-oracle form (off: it helps the rooms but splits a landing seed).
Everything else tried, pooled over indoor seeds 0-7 and the defaults plus ``ba_huber_px`` 1.9 / 2.1 and
``reprojection_threshold_px`` 2.4 / 2.6 (40 runs; defaults 7.63 %, median 7.30, seg 8.14 %, 149 maps, from the events
41.9 %), was worse (code in commit e40ed26, reverted): a pair gate skipping keyframe pairs whose baseline over the median
depth is below 0.5 times their rotation angle (turn pairs) 8.58 % (+0.94 +- 0.51, 16 better; seg +0.32 +- 0.44); that
gate at 1.0 only for coasted keyframes 8.53 % (+0.89 +- 0.52; seg -0.14 +- 0.39; 161 maps); a depth anchor in the
local BA (range factors holding the points' distances from the fixed poses, their mean to 2 %) 8.59 % (+0.96 +- 0.57;
seg +1.20 +- 0.55); each PnP pose re-solved with its camera centre held to the constant-velocity prediction (sigma the
predicted step plus 0.005 median depths) 8.72 % (+1.09 +- 0.58; seg +0.59 +- 0.57); ``ba_fixed_keyframes`` 2 8.73 %
(+1.09 +- 0.53); ``intermediate_observations`` 7.97 % (+0.34 +- 0.55; seg +0.21 +- 0.44).

Where a tracked indoor map's scale wanders (session 29, ``/tmp/s29/scale29``: ``diag.py`` is the hook above on the
session-29 defaults, ``ana.py`` lists one map's keyframes, ``ana2.py`` / ``ana3.py`` / ``ana4.py`` sum up; indoor
event-only seeds 0-7, defaults 3.73 %; the 13 maps with at least four keyframes placed by PnP, 84 keyframes, mostly the
legs): the points keep the map's scale, the keyframe steps do not. Within a map each keyframe's depth scale (final map)
varies by 0.09 in log (seed 4's last map 0.43-0.70, 0.16), a keyframe's new points sit at 0.93 of its old points' depth
(log mean -0.07, sd 0.17, 66 keyframes with at least five new points: the shrink above, now small), and a BA of a mature
window leaves the scale where it was (+0.3 %, 9 BAs; a young map's BA +10.5 % on average, points and poses together).
The keyframe steps' lengths over the true ones (final map) vary by 0.59 in log (seed 4's last map 0.17-11.8 (1.07), its
first steps 4.5 and 11.8 times too long at 77-84 deg/s, its last five 0.17-0.41; seed 0's first map 0.26-1.80), their
ratio to the depth scale by 0.56: the 7-pose Sim(3) scales of :mod:`evpose.slam.pose_refit` are these steps. Per PnP
keyframe step (74 steps, poses at insertion, in the older keyframe's camera frame) the rotation error is 2.0 / 1.9 deg
RMS about x / y and the translation error (over the depth scale) 110 / 113 mm RMS along x / y against a true step of 74
mm (median), and the two go together: correlation of the rotation error about y with the translation error along x
-0.65, about x with along y +0.94 (about y with along y +0.08); 2 deg at the rooms' ~2 m depth is 70 mm, a whole step.
Each step slides along the rotation-translation valley of a narrow view, which the image cannot tell apart; seed 4's
last map walks it steadily (-0.7 to -2.8 deg about y on each of its last 11 steps, 2.2-2.9 s, x error +29 to +106 mm).
Nothing per step flags it (Spearman of the rotation error / |log step ratio| with the points seen at insertion +0.06 /
-0.10, with the true rotation rate -0.14 / +0.22, with the keyframes in the map -0.10 / -0.34; rotation error (all axes)
under 30 points 2.8 deg RMS, over 30 3.1 deg). So gating new points by the old points' depths, a minimum baseline over
depth for triangulation, or more fixed keyframes in the BA act on what is already right; the lever is the keyframe
steps' rotation, while the map is built. Oracles: the true rotation between consecutive keyframes as a prior of the
event-only local BA (``oracle_stmt.txt``, run through ``run.sh``; sigma 0.2 deg, in place of the gyro priors of
event-inertial maps): indoor seeds 0-7 3.730 -> 2.722 % (paired -1.01 +- 0.82, 5 better; seed 4 9.81 -> 3.32 %; the step
lengths then follow the depth scale: seed 0's last map 0.78-0.86 at a depth scale of 0.72-0.78, step over depth scale
0.03 in log against 0.12, seed 4's last map, born later, 1.43-1.49 at 1.32-1.41), held-out 8-19 3.745 -> 2.568 % (-1.18
+- 0.75, 8 better, 4 worse; within 2 % 2 -> 6; segment metric -0.94 +- 0.48); at 1 deg 3.039 % (-0.69 +- 1.04, 4 better)
and 3.417 % (-0.33 +- 0.62, 4 better, 8 worse): a rotation source must hold a keyframe step to well under 1 deg (the
steps' own error is 2-3 deg) to be worth about a point. After the fact it is no lever: each PnP-placed MCI pose
re-solved on the final points with its rotation taken from the truth and only its translation solved (``rotoracle.py``
on jit29's captures, seeds 0-7 at the session-28 defaults, 3.904 %; the same re-solve with its own rotation 3.699 %, as
``refit_tracked_poses``) gives 5.837 % with the map's frame fitted to the true orientations, 4.068 % with the reference
keyframe's rotation and the true rotation since it: the points were triangulated from the same traded steps and hold the
trade. A constant-rotation-rate factor in the BA (``TrackingConfig.ba_rotation_rate_prior_deg_s``, figures there) did
not hold it: at 80 deg/s seed 4's legs were re-drawn into other maps, not mended (its last map born 0.7 s later; step
ratios 0.15-0.26 at a depth scale of 0.3), and the pooled 40 runs got no better.

A rotation source from the images themselves (session 30, :mod:`evpose.slam.room_axes`): the steps' error lies about
the camera's x / y / z axes at 2.0 / 1.9 / 1.1 deg RMS, in world terms tilt 2.4 and yaw 1.8; the true up direction
alone as a 0.2 deg prior (yaw free) gave seeds 0-7 3.94 -> 2.52 %. The rooms' edges along their three axes measure a
keyframe's rotation to a median 0.25 deg where all three show (57 % of the BA's keyframes in situ); as BA priors
(``TrackingConfig.ba_room_prior_deg``, off) they gave the 40 pooled runs of seeds 0-7 3.29 -> 2.73 % (mostly seed 4)
and the 60 of held-out seeds 8-19 3.70 -> 3.44 % (-0.26 +- 0.24), segment metric unmoved, and landing 0-23 1.32 ->
1.91 %.

Why young indoor maps starve, and why feeding them does not pay (session 34, issue 9; ``/tmp/s34/feed34/``: ``run.py``
is session 33's harness writing per-MCI counts, ``young.py`` the per-map start / decay / untracked-time / ATE split,
``diag.py`` + ``diag_ana.py`` where a young map's point tracks go, ``stretch.py`` / ``gtrate.py`` by stretch and true
turn rate, ``cmp.py`` paired). Main's defaults, indoor event-only seeds 0-39 (3.017 %): 225 map starts from a median
35 points (q10 18, q90 85); of the 186 starts under 70 points 179 have their last PnP pose within 0.3 s of the start
(median tracked map points at 0.05 / 0.1 s: 5 / 1 for 20-30 point starts, 7 / 1 for 30-45, 21 / 9 for 45-70), of the
39 starts of 70 or more 5 (79 / 70 / 59 / 57 tracked at 0.05 / 0.1 / 0.2 / 0.3 s). Of the 288 ms untracked per run,
239 (83 %) follow a map whose visual tracking ended within 0.3 s of its start; 63 % of the squared position residual
(each map Sim(3)-aligned) lies in maps' first 0.3 s, and cutting those poses (maps re-aligned) gives 2.26 %. The
starts in the room's turn (0.84-1.91 s: 83 starts, median 27 points; true turn rate 60-100 deg/s at 87 starts) never
track visually past 0.3 s; the first stretch's 63 starts once, the last stretch's 79 starts 40 times. The point tracks
die in KLT, not in the pose step: per MCI 36 % at ages 0-0.02 s, 27 % at 0.02-0.05 s, 14 % at 0.05-0.1 s, 11-13 % later
(seeds 0-19); the pose step's net change in the first 0.1 s is -1 to +4 % on PnP-placed MCIs (re-finding less PnP
outliers) and -10 to -11 % on coasted ones (tracks the coast contradicts). The landing
(seeds 0-23) starts from 38-68 points and no map starves young. Feeding young maps (``TrackingConfig.young_map_s``,
``young_map_max_rate_dps``, ``InitializationConfig.reference_tracks``; figures there) and a stricter start
(``min_triangulated`` 30) all made the rooms worse: a fed map lives on where a starved one would have coasted, and in
these rooms the coasted maps score better than the visually tracked ones (as the notes of
``FeatureConfig.klt_min_support_ratio`` found for the turn).

How map points end and what carries a PnP map's scale (session 35, issue 9; ``/tmp/s35/scale35/``, main a3cb2d0,
event-only; ``die.py`` follows every (track, point) association across the MCIs placed by PnP on the same map,
``share.py`` counts the points PnP-placed keyframes share, ``tri.py`` where triangulation candidates go, ``refy.py``
the projection search's yield, ``kltdie.py`` which KLT filter ends a map point's track). Session 34's "a keyframe
shares none with the third before" was one map (seed 0's first): over the maps with at least four PnP-placed
keyframes, indoor seeds 0-5 (10 maps, 69 keyframes) share a median 32 / 25 / 21 / 18 points with the keyframe 1 / 2 /
3 / 5 before, the landing seeds 0-3 42 / 30 / 23 / 14. Per MCI an association ends indoors (seeds 0-4) at 16.5 %
(KLT 10.3 away from the border, 1.9 near it, PnP outlier 4.2, culled 0.03), on the landing (seeds 0-3) at 14.5 % (9.6 / 2.3
/ 2.7 / 0.04); over seeds 0-19 keyframes come on 36 / 35 % of the PnP MCIs and these hold 40 / 41 tracked map points: per MCI the
two scenes lose points alike, but indoor MCIs come every 15.6 ms against 38 ms, so per second the rooms hand the
scale on 2.4 times as often (23 against 9.3 keyframes a second). Map-point tracks ended by KLT indoors (seeds 0-5,
14.9 % per step): the forward-backward error over 1 px 9.7 %, the backward pass not converging 4.0, the forward one
0.7, leaving the image 0.6; the forward-backward error of converged map tracks is a median 0.03 px, 90 % 1.05, 95 %
6.5, only 2.1 % of them within 1-2 px: KLT loses them outright, the test is not too strict. The projection search
(KLT from keyframe MCIs, refine pass) finds 2.1 of 47 untracked window points per MCI indoors (59 tries, 10.2 within
3 px, 3.15 pass the forward-backward test; forward results a median 7.7 px from the projection; landing 2.4 of 69).
Triangulation at PnP keyframes indoors (seeds 0-4, per keyframe): 23.2 candidates, 10.0 held back by the pair gate
(``min_pair_parallax_deg``), 2.9 under ``min_triangulation_deg``, 9.0 made (landing seeds 0-3: 18.5 / 2.4 / 0.7 /
14.5). Levers tried against main's defaults (indoor seeds 0-19, 2.705 %; paired mean +- standard error, seeds better
/ worse): ``min_pair_parallax_deg`` 1.5 +0.574 +- 0.266 (6 / 11), 3.0 +0.308 +- 0.300 (10 / 10);
``intermediate_observations`` +0.142 +- 0.307 (9 / 11); ``ba_scale_anchor`` 0.005 +0.516 +- 0.241 (8 / 12), 0
+0.864 +- 0.457 (5 / 15); ``search.fuse_radius_px`` 1.5 +0.129 +- 0.196 (10 / 10); ``search.refine_radius_px`` 5
+0.179 +- 0.374 (7 / 13); the search's forward-backward limit 2 px instead of 1 (code not kept) +0.237 +- 0.315
(10 / 10); ``window.feature_displacement_px`` 5 +0.496 +- 0.514 (least tracked 65.7 %); ``window.min_events`` 600
+0.359 +- 0.433 (7 / 13, least tracked 71.5 %); fewer keyframes: ``keyframe_displacement_px`` 30 and
``keyframe_displacement_min_s`` 0.1 (figures there) gain on seeds 0-19 but not on the held-out seeds or the landing.

Where the landing's one mature map drifts along the track (session 38, ``/tmp/s38/lm38``: ``pieces.py`` cuts each
landing seed's main map into 0.15 s pieces (log of the aligned chord over the true one, mean PnP inliers, new
keyframes), ``kfsteps.py`` lists its keyframe-to-keyframe steps (aligned length over the true one, inliers, map points
seen, KLT tracks), on main fd512ff's defaults, tag ``fin``): every landing seed flies the same path, and in every seed
the mature map's pieces spread most at 1.95-2.25 s (log chord sd over seeds 0.18 / 0.18 / 0.15 against 0.04-0.11 at
0.6-1.8 s but 1.05 s (0.16) and 0.08-0.09 at 2.4-2.55 s), just after the flight's slowest stretch (2.3 m/s at 1.8-1.95
s, 4.3 m up): PnP holds its fewest map points there (mean inliers 29 / 26 / 33 against 32-54 elsewhere in the mature
map), the tracked-points trigger inserts a keyframe every 80-84 ms (120-178 ms over 1.05-1.95 s) and each adds 11-14
points. Seed 12's four keyframe steps at 2.05-2.29 s come out 1.23-1.63 times the true length at 23-26 points seen, then
return to within 10 % (a 0.3 s excursion); five of seed 17's six steps at 2.12-2.50 s are 0.58-0.85 times it (17-42
inliers) and the shrink stays. Over the mature pieces of seeds 0-23 the error grows as the points thin (RMS log chord
0.140 at 20-28 inliers, 0.131 at 28-35, 0.101 at 35-45, 0.154 over 45, at the end; Spearman of |log chord| with inliers
-0.16), but seeds 12 and 17 are not the starved ones (mean inliers over 1.9-2.4 s 30.2 and 26.2 against 22.0-37.0 over
seeds; without seed 4's loss the per-seed Spearman of ATE with it is -0.41, p 0.05). Existing levers on it, paired
against ``fin``, did not hold on held-out seeds (figures at ``min_triangulation_deg`` and ``ba_fixed_keyframes``).

Which stage hands a shrunk step on (session 40, ``/tmp/s40/eo40``: ``kfdiag.py`` hooks every keyframe insertion and
local BA, ``kfana.py`` gives each insertion's h = log of its new keyframe step over the step before, both over the true
steps: as PnP hands it in, after the insertion's BA, in the final map; main 8b52aca's defaults; truth offline only).
At PnP-placed insertions indoors the new step comes in shorter than the one before on all 18 seeds looked at (0-13, 21,
33, 44, 52; mean h -0.09 to -0.53 per insertion, 53-100 % of insertions below 0), and the final maps keep much of it
(mean h -0.53 to +0.07); on the landing (0, 1, 2, 12, 17) PnP hands in -0.02 to -0.14 and the mature map's BAs take it
back (final -0.04 to +0.02). Indoors h is lower where the MCIs come farther apart than at the keyframe before (event
rate falling as the room's turn slows: -0.45 against -0.17 at a level rate; Spearman -0.14, p 0.03, 228 insertions;
``lagcorr.py``); the true rate falls from 74 to 21 deg/s over 0-0.8 s and from 109 to 22 over 1.65-2.65 s, the
over-2 % rooms' bad maps lie mostly there (0.47-0.85 s, 1.9-3.0 s), and the maps of 0.86-1.9 s hold their scale.
A young map's BA can also make it worse (indoor 5's last map, the BA stall of ``TrackingConfig.cull_min_depth_ratio``
removed: -1.05 summed at PnP, -3.76 after the BAs).

Not the MCI's time stamp (session 40, ``/tmp/s40/mt40``: ``tdiag.py`` logs each MCI's window event times, ``tana.py``,
``kfpred.py``, ``dphase.py``; truth offline). Within a window the event rate barely changes. Indoor 0-15 (3078 MCIs),
the stamp being the window's middle (``MciConfig.reference_fraction`` 0.5), the median event time sits -0.96 to +0.65 ms
(10-90 %; median -0.07, mean -0.84) from it in the slowing turns (0.05-0.8 s, 1.65-2.65 s; windows a median 35 ms: a
linear rate change of -2 % per window), -0.16 to +0.30 ms elsewhere (12 ms windows); landing 0-6 -4.3 to +2.5 ms of 67
ms. Moving the true poses to those times changes the PnP insertions' h (``kfpred.py``, eo40's 177 insertions of seeds
0-13, measured mean -0.245) by +0.004 on average (RMS 0.035, correlation with h -0.15), and consecutive OK steps' h by
+0.0002 (RMS 0.036 against the measured 0.81). Per map the estimated rotations fit the truth no better at the median
event times than at the stamps (pooled squared angle 5.501 -> 5.499). Online, the stamp and warp reference at the median
event (option tried, not kept; ``q.sh mc``, ``cnt.py ds10 mc``): indoor 0-53 1.825 -> 1.816 % (-0.009 +- 0.110, 28
better, 26 worse), fresh 54-61 1.744 -> 1.949 (+0.205 +- 0.219; within 2 % 7 -> 5), landing 0-23 1.470 -> 1.799 (+0.329
+- 0.435, 15 worse; median change without 4 / 12 / 17 +0.144), 24-35 1.237 -> 1.534: chaotic re-draws, worse on the
landing.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import TrackingConfig
from evpose.slam.geometry import camera_depths, good_triangulation, triangulate


def need_keyframe(m: SlamMap, tr_ids: np.ndarray, tr_uv: np.ndarray, n_tracked_points: int, cfg: TrackingConfig,
                  t_us: int | None = None) -> bool:
    """The paper's heuristics: tracked map points fell below a share of the last keyframe's, or key points moved far
    (the latter, with ``t_us`` given, only :attr:`TrackingConfig.keyframe_displacement_min_s` after the last keyframe)."""
    last = m.keyframes[-1]
    point_tracks = _point_tracks(m)  # once: a set per key point made this quadratic
    n_last = sum(1 for tid in last.obs if tid in point_tracks)
    if n_last and n_tracked_points < cfg.keyframe_tracked_ratio * n_last:
        return True
    if t_us is not None and cfg.keyframe_displacement_min_s > 0 and (t_us - last.t_us) / 1e6 < cfg.keyframe_displacement_min_s:
        return False  # too soon after the last keyframe for a displacement keyframe: each one hands the scale on anew
    common = [(last.obs[t], uv) for t, uv in zip(tr_ids.tolist(), tr_uv) if t in last.obs]
    if not common:
        return True
    disp = np.median([np.linalg.norm(a - b) for a, b in common])
    return bool(disp > cfg.keyframe_displacement_px)


def young_map(m: SlamMap, t_us: int, cfg: TrackingConfig, T_wc: np.ndarray | None = None) -> bool:
    """``m`` is younger than :attr:`TrackingConfig.young_map_s` at ``t_us`` (time since its first keyframe) and, with
    ``young_map_max_rate_dps`` and the pose ``T_wc`` given, has turned at most that fast since its first keyframe."""
    if cfg.young_map_s <= 0 or not m.keyframes:
        return False
    dt = (t_us - m.keyframes[0].t_us) / 1e6
    if dt >= cfg.young_map_s:
        return False
    if cfg.young_map_max_rate_dps > 0 and T_wc is not None and dt > 0:
        R = m.keyframes[0].T_wc[:3, :3].T @ T_wc[:3, :3]
        deg = np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))
        return bool(deg <= cfg.young_map_max_rate_dps * dt)
    return True


def young_triangulation(cfg: TrackingConfig) -> TrackingConfig:
    """The triangulation settings of a young map's keyframes (``young_min_*`` in place of ``min_*``)."""
    return replace(cfg, min_triangulation_deg=cfg.young_min_triangulation_deg, min_pair_parallax_deg=cfg.young_min_pair_parallax_deg)


def visual_ba_window(m: SlamMap, cfg: TrackingConfig, event_only: bool) -> tuple[int, int]:
    """Keyframes the visual local BA optimises after a keyframe insertion, and how many of the oldest of them it holds
    fixed: ``ba_window`` (event-only, when set) or ``local_window`` keyframes, never reaching back past the map's newest
    visual segment (:attr:`SlamMap.segment_start_kf`)."""
    span = cfg.ba_window if event_only and cfg.ba_window > 0 else cfg.local_window
    window = min(span, sum(k.id >= m.segment_start_kf for k in m.keyframes))
    n_fixed = cfg.ba_fixed_keyframes if event_only and len(m.keyframes) > span else 1
    return window, n_fixed


def _point_tracks(m: SlamMap) -> set[int]:
    return {p.track_id for p in m.points.values()}


def insert_keyframe(m: SlamMap, t_us: int, T_wc: np.ndarray, tr_ids: np.ndarray, tr_uv: np.ndarray, track_to_point: dict[int, int]) -> Keyframe:
    """Add a keyframe observing every current track; tracks with map points add an observation to their point."""
    kf_id = m.keyframes[-1].id + 1 if m.keyframes else 0
    kf = Keyframe(kf_id, int(t_us), T_wc.copy(), {int(t): np.asarray(uv, np.float64).copy() for t, uv in zip(tr_ids.tolist(), tr_uv)})
    m.keyframes.append(kf)
    for tid, uv in kf.obs.items():
        pid = track_to_point.get(tid)
        if pid is not None and pid in m.points:
            m.points[pid].obs[kf_id] = uv
    return kf


def triangulate_new_points(m: SlamMap, K: np.ndarray, kf: Keyframe, track_to_point: dict[int, int], cfg: TrackingConfig, next_point_id: int,
                           predicted: bool = False) -> int:
    """Triangulate tracks of ``kf`` without a point against the oldest keyframe that saw them; returns the next free point id.

    ``predicted``: ``kf`` sits at a pose no image placed (an event-only coast's prediction); with
    :attr:`TrackingConfig.coast_depth_level` its new points then take the depth level of the older points.

    With :attr:`TrackingConfig.rejoin_pair_check`, in a re-joined map (:mod:`evpose.slam.map_rejoin`) a pair reaching
    back past the newest visual segment (:attr:`SlamMap.segment_start_kf`) makes a point only if it also reprojects in
    every keyframe between the pair that saw the track: a KLT track can outlive the loss of a map, drifting onto
    whatever the events show next, so the same track id in the older segment may be another scene point."""
    by_kf: dict[int, list[int]] = {}
    for tid in sorted(kf.obs):
        if tid in track_to_point:
            continue
        for old in m.keyframes[:-1]:
            if tid in old.obs:
                by_kf.setdefault(old.id, []).append(tid)
                break
    z_med = _median_depth(m, kf, track_to_point) if cfg.min_pair_parallax_deg > 0 else None
    for old_id, tids in sorted(by_kf.items()):
        old = m.keyframe(old_id)
        if z_med is not None and np.degrees(np.linalg.norm(kf.T_wc[:3, 3] - old.T_wc[:3, 3]) / z_med) < cfg.min_pair_parallax_deg:
            # Too short a baseline for the scene depth: every track's parallax is near the per-point threshold, and the
            # ones whose noise pushes them over it come out too near. Wait for a later keyframe with a wider baseline.
            continue
        uv1 = np.array([old.obs[t] for t in tids])
        uv2 = np.array([kf.obs[t] for t in tids])
        X = triangulate(K, invert_pose(old.T_wc), invert_pose(kf.T_wc), uv1, uv2)
        good = good_triangulation(K, old.T_wc, kf.T_wc, uv1, uv2, X, 2.0 * cfg.reprojection_threshold_px, cfg.min_triangulation_deg)
        between = [b for b in m.keyframes if old.id < b.id < kf.id] if cfg.intermediate_observations else []
        across = [b for b in m.keyframes if old.id < b.id < kf.id] if cfg.rejoin_pair_check and old.id < m.segment_start_kf else []
        for k in np.flatnonzero(good):
            tid = tids[k]
            if not all(_reprojects(K, b.T_wc, X[k], b.obs[tid], 2.0 * cfg.reprojection_threshold_px) for b in across if tid in b.obs):
                continue  # a pair across a re-join whose track changed scene point on the way
            obs = {old.id: uv1[k], kf.id: uv2[k]}
            for b in between:
                uv = b.obs.get(tid)
                if uv is not None and _reprojects(K, b.T_wc, X[k], uv, 2.0 * cfg.reprojection_threshold_px):
                    obs[b.id] = uv
            m.points[next_point_id] = MapPoint(next_point_id, X[k].copy(), dict(sorted(obs.items())), tid, kf.id)
            track_to_point[tid] = next_point_id
            next_point_id += 1
    if predicted and cfg.coast_depth_level:
        _level_new_depths(m, kf, cfg.coast_depth_level_keyframes)
    return next_point_id


def _level_new_depths(m: SlamMap, kf: Keyframe, lookback: int) -> None:
    """Scale the depths in ``kf`` of the points just triangulated at it (``created_kf``) about its camera centre so
    that their median depth is the median depth of the older points that ``kf`` or, failing that, the nearest of the
    ``lookback`` keyframes before it sees. ``kf`` sits at a predicted pose whose baseline carries the coast's held
    velocity, not the map's scale."""
    new = [p for p in m.points.values() if p.created_kf == kf.id]
    if not new:
        return
    z_ref = None
    for k in reversed(m.keyframes[-(lookback + 1):]):
        z = _depths(k, [p.xyz for p in m.points.values() if k.id in p.obs and p.created_kf != kf.id])
        if z.size >= 3:
            z_ref = float(np.median(z))
            break
    z_new = _depths(kf, [p.xyz for p in new])
    if z_ref is None or z_new.size == 0:
        return
    s = z_ref / float(np.median(z_new))
    c = kf.T_wc[:3, 3]
    for p in new:
        p.xyz = c + s * (p.xyz - c)


def _depths(kf: Keyframe, X: list) -> np.ndarray:
    """Depths (z in ``kf``'s camera) of the points ``X`` in front of it."""
    if not X:
        return np.zeros(0)
    z = camera_depths(kf.T_wc, X)
    return z[z > 0]


def _reprojects(K: np.ndarray, T_wc: np.ndarray, X: np.ndarray, uv: np.ndarray, max_err_px: float) -> bool:
    """``X`` lies in front of the camera ``T_wc`` and projects within ``max_err_px`` of ``uv``."""
    T_cw = invert_pose(T_wc)
    Xc = T_cw[:3, :3] @ X + T_cw[:3, 3]
    if not Xc[2] > 0:
        return False
    q = Xc[:2] / Xc[2] * np.array([K[0, 0], K[1, 1]]) + np.array([K[0, 2], K[1, 2]])
    return bool(np.linalg.norm(q - uv) < max_err_px)


def _median_depth(m: SlamMap, kf: Keyframe, track_to_point: dict[int, int]) -> float | None:
    """Median depth in ``kf`` of the map points it observes, map units (None without any in front)."""
    X = [m.points[track_to_point[t]].xyz for t in kf.obs if track_to_point.get(t) in m.points]
    if not X:
        return None
    T_cw = invert_pose(kf.T_wc)
    z = np.asarray(X) @ T_cw[2, :3] + T_cw[2, 3]
    z = z[z > 0]
    return float(np.median(z)) if z.size else None


def cull_points(m: SlamMap, K: np.ndarray, track_to_point: dict[int, int], cfg: TrackingConfig, min_depth_ratio: float = 0.0) -> int:
    """Remove points behind a keyframe or reprojecting badly, and young points few keyframes confirmed; returns how many.

    ``min_depth_ratio`` > 0 also removes points nearer a keyframe observing them than that share of the keyframe's
    median point depth (:attr:`TrackingConfig.cull_min_depth_ratio`): a point slid into a camera centre makes the
    local BA's normal equations singular."""
    if not m.points:
        return 0
    kf_index = {kf.id: i for i, kf in enumerate(m.keyframes)}
    T_cw = np.stack([invert_pose(kf.T_wc) for kf in m.keyframes])
    newest = m.keyframes[-1].id if m.keyframes else 0
    pids = sorted(m.points)
    # One row per observation, vectorised: point index, keyframe index, observed pixel.
    rows = [(j, kf_index[kid], uv) for j, pid in enumerate(pids) for kid, uv in m.points[pid].obs.items() if kid in kf_index]
    bad = np.zeros(len(pids), bool)
    if rows:
        pj = np.array([r[0] for r in rows])
        kk = np.array([r[1] for r in rows])
        uv = np.array([r[2] for r in rows], np.float64)
        X = np.stack([m.points[pid].xyz for pid in pids])[pj]
        Xc = np.einsum("nij,nj->ni", T_cw[kk, :3, :3], X) + T_cw[kk, :3, 3]
        z = Xc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            proj = Xc[:, :2] / z[:, None] * np.array([K[0, 0], K[1, 1]]) + np.array([K[0, 2], K[1, 2]])
            err = np.linalg.norm(proj - uv, axis=1)
        obs_bad = ~(z > 0) | ~np.isfinite(err) | (err > 2.0 * cfg.reprojection_threshold_px)
        if min_depth_ratio > 0:
            med = np.full(len(m.keyframes), np.nan)
            for i in np.unique(kk):
                zi = z[(kk == i) & (z > 0)]
                if zi.size:
                    med[i] = np.median(zi)
            with np.errstate(invalid="ignore"):
                obs_bad |= z < min_depth_ratio * med[kk]  # a keyframe without a depth in front (nan) culls nothing here
        np.logical_or.at(bad, pj, obs_bad)
    removed = []
    for j, pid in enumerate(pids):
        p = m.points[pid]
        if bad[j] or (newest - p.created_kf >= 3 and len(p.obs) < cfg.min_observations):
            removed.append(pid)
    for pid in removed:
        tid = m.points.pop(pid).track_id
        if track_to_point.get(tid) == pid:
            del track_to_point[tid]
    return len(removed)
