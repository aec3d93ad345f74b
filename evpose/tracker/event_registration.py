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

Session 20 (``/tmp/s20/res7/``): how much of its start's error a whole ``full`` step (T_align, field, events, priors)
keeps, by re-running it from the prediction moved 0.1 deg / 5 mm along each camera-frame tangent axis, the previous
pose moved alike so the motion twist stays (``probe.py``; every 20th update of seeds 0 and 4, 38 probes per
resolution). The mean echo ``S`` (result moved per start moved; rotation then translation, rad and m) has the diagonal
0.50 / 0.27 / 0.26, 0.46 / 0.58 / 0.35 at 240x180 and 0.29 / 0.26 / 0.18, 0.32 / 0.30 / 0.23 at 346x260, plus
tilt-to-shift couplings (``ty`` from ``rx``, ``tx`` from ``ry``, ``tz`` from ``ry``, ``tz`` from ``rx``) of 0.73 / -0.70 /
0.46 / 0.41 and 0.37 / -0.71 / 0.75 / 0.23 m/rad; single probes scatter by 0.13-0.34 about these means. (Moving the
prediction alone, which also changes the twist the events are placed along, the diagonal reads 0.75-1.1.) So at
240x180 a registration keeps about twice the share of the prediction's error that it keeps at 346x260. Handing the
fusion what that model says the registration measured, ``z' = P Exp(G^-1 Log(P^-1 z))`` with covariance
``G^-1 C G^-T``, ``G = I - S``, ``P`` the prediction (``run_deecho.py``; ``full``, 2 s landing, mean ATE mm / ARE deg):
240x180 seeds 0-7 7.325 / 0.0802 -> 6.874 / 0.0838 (the mean ``S`` in the tracker instead of the median 6.838; only
the diagonal 7.98, only the couplings 7.00, ``S`` x 0.5 / x 1.5 6.97 / 14.06 mm), but held-out seeds 8-11 6.855 /
0.0744 -> 7.486 / 0.0909 (``S`` x 0.5 6.944): it cuts the seeds with large errors (seeds 0 / 2 / 4 / 11 10.65 / 9.60
/ 11.71 / 12.22 -> 9.05 / 6.69 / 10.08 / 11.81) and costs the good ones about 1 mm (3 / 8 / 10: 4.07 / 5.79 / 2.79 ->
4.97 / 6.98 / 3.95), as trusting the registrations more does. 346x260 seeds 0-7 (5.305 / 0.0589) with its own ``S``
5.283 / 0.0594; with ``fusion.registration_covariance_scale`` 15 / 10 5.324 / 5.342, with 240x180's ``S`` at 10 5.424.
Not kept: a fixed ``S`` is a property of the benchmark's seeds, and an online one would cost a registration per axis.
What was kept instead: the fused modes' prior towards the prediction widens on coarse sensors
(``registration.fused_prior_reference_pixel_mrad``), which takes the echo's cause (the prior's larger share at
240x180) at its source.

Session 29 (``/tmp/s29/reg29/``: ``run.py`` with ``LOG=1`` records every update's prediction, field registration,
combined registration and fused pose; ``budget.py``, ``signed.py``): the error budget at 240x180, ``full``, 2 s landing
seeds 0-7 (6.955 mm), camera frame at the truth, RMS over every update and of the 50-update moving mean (the slow
part). Fused: rotation about x / y / z 57.6 / 30.5 / 47.4 mdeg, translation x / y / z 2.86 / 4.97 / 4.40 mm (y with
the rotation about x: the tilt/sideways pair; z: the height). The combined registration the graph gets: 90 / 96 / 61
mdeg, 6.75 / 6.26 / 4.93 mm, its slow part 64 / 53 / 53 mdeg, 4.09 / 4.70 / 3.74 mm; the field's alone, slow, 4.83 /
4.82 / 3.78 mm (the events take ~0.7 mm off x, little off y and the height). So the fused error is the registrations'
slow error (y 4.87 / height 4.30 mm fused, slow), the graph removing their fast part and no more, and that slow error
changes sign from seed to seed (per-seed mean height error of the registrations -3.7 to +3.7 mm; tilt -76 to +38 mdeg
with the sideways shift of the same sign, -6.1 to +3.7 mm): no bias a constant correction could take out. The largest
parts, y and the height, need registrations whose slow error is ~30 % smaller to reach 5 mm. Kept: the events' gate
and Huber scale shrunk on coarse sensors (``angle_reference_pixel_mrad``, ``angle_pixel_exponent``: 1.5 / 0.5 ->
0.72 / 0.24 px at 240x180; 6.955 -> 6.521 mm, held-out seeds 8-11 6.807 -> 6.225, 3 s landing seeds 0-3 / 4-7
18.90 / 26.41 -> 16.22 / 23.17; fused y / height 4.54 / 4.24 mm), and with them the events trusted more there
(``covariance_pixel_exponent``: ``covariance_scale`` 300 -> 70 at 240x180; seeds 0-7 5.532 mm, 8-11 5.257, 3 s 14.13
/ 17.72). Not kept (seeds 0-7, 6.955 mm): ``registration.robust_scale`` 0.45 / 0.2 6.964 / 6.845 (0.2 with the gate and
Huber scale x 0.69 6.614, held-out 6.408-6.446: within the spread);
``time_surface.eta_ms`` 14.4 / 7 8.750 / 7.259; ``registration.max_points`` 1500 6.918; the field's covariance from
its inliers (``registration.residual_variance``) 7.596; ``prior_residual_px`` 0.3 6.932; ``association_radius_px``
1.5 7.041 mm.

Session 30 (``/tmp/s30/map30/``: ``run.py`` with ``MAPX``, ``mapx.py``, ``errs.py``, ``nearerr.py``): what the built map
still costs with these defaults (``full``, 2 s landing from ground truth, mean ATE). The built map's error along each
point's edge normal to the nearest true edge (points within 3 cm of one): painted points 12.2 mm RMS (bias +1.9 mm; 8-19
% of them farther than 3 cm; seeds 0-3), geometric feet / tops / vertical edges 1.34 / 1.30 / 1.05 mm over the whole
map but 2.8 / 3.8 / 1.4 mm within 4 m of the pad (seed 0): the pad's 15 cm sides make no region, and its rims were
placed point by point from one to three side points (pieces 10-40 cm long, p10 / p90 -5 / +6 mm; seed 0's top rim
traced 7 degrees tilted, 72 mm RMS). The oracle, every map point moved onto its nearest true edge with its attributes
kept: 346x260 seeds 0-3 5.335 -> 4.19 mm, but 240x180 seeds 0-7 5.56 -> 5.66 mm (seeds 0-2 1-1.5 mm better, 3-4 1-2
mm worse). :mod:`evpose.mapping.step_lines` (one line per straight run of a low step's edge, fitted to all of its
face's points; rims near the pad 2.9 / 3.9 -> 2.1 / 3.0 mm RMS) took seeds 0-11 to 4.471 / 5.313 mm (346x260 /
240x180, from 4.621 / 5.438) but held-out seeds 12-23 from 5.551 / 6.445 to 5.653 / 6.490: within the noise, left off.
On its map (seeds 0-11): the oracle 4.241 / 5.620 mm, the painted points alone on the truth 4.452 / 5.367, the painted
points farther than 3 cm left out 4.479 / 5.306, the painted edges squared to the pad (``albedo_axis_snap_deg`` 12,
their RMS error 11.9 -> 10.8 mm) 4.595 / 5.626. Where the whole-map oracle's gain hides, one class of points at a
time moved onto the truth (built map without step_lines, seeds 0-11, against 4.621 / 5.438 mm): the top rims (the
pad's and every box's upper edges) 3.314 mm at 346x260 (ARE 0.0575 -> 0.0382 deg) and 4.871 mm at 240x180 (0.063 ->
0.055 deg), both under the 5 mm target; the feet 5.552 mm at 240x180 (worse, which is why the whole-map oracle is no
better there), the vertical edges 5.391. At 346x260 the pad's top rims alone 4.394 mm, the other top rims alone (the
crates' and buildings', crease-snapped) 3.817 mm. Their error (along the edge normal, within 3 cm of the truth, seeds
0-11 at 346x260): the pad's top rims 4.66 mm RMS (20 % of points > 5 mm off, 3.5 % > 3 cm; step_lines takes the pad's
to ~1-2 mm), the other top rims within 4 m of the pad 1.84 mm RMS, bias -0.43 mm (inward, onto the top face), median
0.69 mm, 17 % > 2 mm (the whole map's 0.80 mm, bias -0.16). So the map still sets a limit, through its top rims: their
1-5 mm RMS cost 0.6-1.3 mm of ATE; placing the crease-snapped top rims more exactly (their inward bias, the
crates near the pad) is the next map work, the feet are better left as built (scripts ``q7.sh``-``q9.sh``). Which top rims are
off, and one fix (``/tmp/s30/rim30/``, :mod:`evpose.mapping.crease_planes`): of the crates' and buildings' top rims near
the pad, 85 % of the squared error is crease-snapped points in whole runs 3-10 mm off on the 0.4-0.5 m crates, whose
faces (19-87 points) hold their neighbours' strays and are tilted 1.5-2.3 degrees by them; refitting the crease planes
without the strip along each crease, trimmed, and squared to the ground within 3 degrees takes those rims to 1.40 mm RMS
(bias 0.00, 2.8 % > 2 mm) but ``full`` (seeds 0-11, this checkout's plain builder 4.625 / 5.453 mm: main's crowding fix
moved seed 0 by 0.05 mm) only to 4.434 / 5.784 mm (4.306 / 5.651 with the feet left as built): better at 346x260, worse
at 240x180 (ARE 0.063 -> 0.070), all within +-1.5 paired standard errors; held-out seeds 12-23 (feet as built) 346x260 5.551 -> 4.858 mm (seeds 21 / 22 10.5 / 8.7 -> 4.8 / 5.7), 240x180 240x180 6.445 -> 6.202 (0-23: 346x260 5.088 -> 4.582 mm, -0.51 +- 0.31, 16 of 24 seeds better; 240x180 5.949 -> 5.927, 13 of 24). So :attr:`evpose.mapping.build.MapBuildConfig.crease_refit` is off (it does not help both resolutions).

Session 31 (``/tmp/s31/rim31/``, ``run2.py`` swaps the events' copy of the map): it is on now (ARE over seeds 0-23 lower at
both resolutions, 240x180 ATE level), and at 240x180 it is this registration reading the better rims that keeps the
gain away: the field on the new map with the events on the plain one 5.949 -> 5.824 mm (-0.13 +- 0.07, every axis a
little better), the events on the new map with the field on the plain one 6.038, the new map for both 5.927 (seeds
0-23). With the better rims the events trade the tilt about x and the sideways error (-15 mdeg, -0.54 mm RMS) for the
tilt about y and an along-motion bias (+12 mdeg, +0.70 mm; the bias +1.70 -> +2.76 mm along the camera's x, the
flight's direction, in every seed alike). The events move the field's pose +2.0 mm ahead along the motion with either
map (their OFF leads); halving the three OFF leads removes it (+0.02 mm, ARE 0.0732 -> 0.0639 deg) but grows the height
and sideways errors (+0.9 mm RMS each): 6.352 mm. At 346x260 the same split (seeds 0-23, 5.088 mm plain): the field on
the new map alone 4.875 (-0.21 +- 0.07, 19 of 24 better), the events on it alone 4.656 (-0.43 +- 0.26), both 4.582;
there too the events on the better rims cut the tilt about x and the sideways error (-15.4 mdeg, -0.82 mm RMS) and
raise the along-motion bias (+1.15 -> +2.43 mm), but that costs only +2.5 mdeg / +0.21 mm RMS against +12.8 / +0.80 at
240x180: the coarser sensor holds the tilt about y against the shift along the motion less well. Figures in the
builder's ``crease_refit``. The crease points' OFF lead kept as an angle on coarser sensors (offlead31,
``crease_off_lead_pixel_exponent`` 1: -0.22 -> -0.153 px at 240x180, 346x260 and the demos unchanged): 240x180 2 s
seeds 0-23 5.927 -> 5.716 mm (-0.21 +- 0.07), held-out 24-35 7.202 -> 6.934 (-0.27 +- 0.15), 36-47 6.522 -> 6.371, ARE
lower on all three, but the 3 s landing (seeds 0-7) 16.99 -> 18.09 mm, every seed worse: an option, off.

Session 31, what the polarity filter does to this stage (issue 7's "the filter cuts registration latency by >= 40 %"
read in ``full``, :mod:`evpose.bench.filter_registration_cost`, figures there): with the filter off
(``polarity.enabled``) the same events enter the association (the noise filters' ``keep``: 3402 per update on the
textured landing, 1293 on the plain one) and 878 / 861 against 902 / 878 are associated (the point's predicted polarity
drops 1.2-2.6 %); this stage's CPU is the same within +-2 % (textured 0.511 against 0.516 ms). The ~65 % of the
textured landing's events ``T_align`` removes are the texture's, off the map's edges, which the association's 2 px
radius leaves out too, at ~20-40 ns an event (association 0.136 ms for 3400 events, 0.09 ms for 1300). Tried, the same
outputs bit for bit, not kept (``/tmp/s31/lat31/gate.py``, ``gate_prototype.diff``; textured seed 0, two alternated
rounds): the kept events gated by ``T_align``'s patches before the association (an event left out when its pixel lies
in the field's box in no patch, valid because a point that moved less than the patch radius minus the association
radius between the prediction and the field registration (with its learned offset) has its association disk inside
its patch; the points that moved more, up to 3 px in a third of the updates through the offsets, got their own disks):
3411 -> 1278 events into the association, which fell 0.138 -> 0.095 ms, but the per-event grid tests took
``_kept_events`` 0.023 -> 0.077 ms and the moved points' test 0.032 ms (the used points read from the whole map):
this stage 0.529 -> 0.587 ms.

Session 32 (``/tmp/s32/edge32/``): the events' offset from the true edge follows neither the edge's normal image speed
nor the pixel size but the event's place in its pixel's burst (first of a passage or after another; the option
``follower_crossings``, off: it costs 1.5 mm at 240x180), and the along-motion bias of 240x180 is not the leads': the
field registration is nearly unbiased along the flight (+0.4 mm), the events' pose +1.9 mm, and their combination lands
beyond both (+2.8 mm, tilt about y -44 mdeg against -21 / -29) on the tilt / shift ridge, which the fusion then carries
into the next prediction (+3.1 mm). Weighing each tangent component on its own keeps it between the two
(``combine_convex``; figures there).
"""

from __future__ import annotations

import numpy as np

from evpose.tracker.event_registration_config import EventRegistrationConfig, scaled_to_pixel  # noqa: F401 (re-exported)
from evpose.tracker.edge_clusters import EdgeTerms, edge_ids_for
from evpose.tracker.event_gauss_newton import passes_compiled, passes_python
from evpose.tracker.event_lag import lead_terms
from evpose.tracker.event_registration_kernels import (NO_EVENT, _associate_nearest, _kept_events, _learn_offsets,
                                                       _pixel_gaps)
from evpose.tracker.contrast_leads import PassageCounts
from evpose.tracker.covered_feet import add_covered_foot_lead, foot_rise
from evpose.tracker.grazing import crease_points, point_leads
from evpose.tracker.pose_combination import combine_poses
from evpose.core.spd_kernels import spd_inverse
from evpose.tracker.registration import _isotropic_information

_NO_POLARITY = np.zeros(0, np.int8)
_NO_TWIST = np.zeros(6)
_NO_TABLE = np.zeros((0, 0, 2), np.float32)
_NO_BURST = np.zeros(0)
"""Placeholders of the kernels' optional inputs (never written)."""


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
        self._rise = None
        if float(config.covered_foot_off_lead_px) != 0 and plane_normal is not None and region_id is not None:
            self._rise = foot_rise(self._base, self._plane_normals, region_id, float(config.crease_radius_m))
            if not config.covered_foot_wall_side:  # the ground's side of the foot only
                self._rise[np.abs(self._plane_normals[:, 2]) < 0.3] = 0.0
        """How far each point's vertical face rises above it (m, 0 = not a foot) for ``covered_foot_off_lead_px``; None = off."""
        self._clusters = edge_ids_for(config.edge_clusters, self._base, self._normals, region_id)
        """Edge id of each map point for ``edge_clusters``; None when that is off."""
        self.offsets = np.zeros(self._base.shape[0])
        """Learned offset of each map point along its unit edge normal, metres."""
        self._width, self._height = int(width), int(height)
        self._last = None
        self.last_events = 0
        """Events associated with a point at the last :meth:`refine`."""
        c = config
        self._burst = (np.array([float(c.follower_crossings), float(c.first_on_lead_px), float(c.follower_on_lead_px),
                                 float(c.first_off_lead_px), float(c.follower_off_lead_px)])
                       if float(c.follower_crossings) > 0 else _NO_BURST)
        self._passages = (PassageCounts(c.contrast, self._base.shape[0], self._base, self._tangents)
                          if float(c.contrast.lone_on_lead_px) != 0 or float(c.contrast.lone_off_lead_px) != 0 else None)
        """Events per pixel passage of each point, for ``contrast.lone_on_lead_px`` / ``lone_off_lead_px``; None when both are off."""
        self._pixel_last = (np.full(2 * self._width * self._height, NO_EVENT, np.int64)
                            if self._burst.size or self._passages is not None else None)
        """Each pixel's latest event time per polarity (us), for ``follower_crossings`` and ``contrast``; None when off."""

    def snapshot(self):
        if self._pixel_last is None:
            return np.copy(self.offsets)
        if self._passages is None:
            return np.copy(self.offsets), np.copy(self._pixel_last)
        return np.copy(self.offsets), np.copy(self._pixel_last), self._passages.snapshot()

    def restore(self, state) -> None:
        offsets = state
        if isinstance(state, tuple):
            offsets = state[0]
            if self._pixel_last is not None:
                self._pixel_last = np.copy(state[1])
        elif self._pixel_last is not None:
            self._pixel_last.fill(NO_EVENT)
        if self._passages is not None:
            self._passages.restore(state[2] if isinstance(state, tuple) and len(state) > 2 else None)
        self.offsets = np.copy(offsets)
        self.points = self._base + self.offsets[:, None] * self._normals
        self._last = None

    def refine(self, T_world_cam: np.ndarray, used: np.ndarray, polarity: np.ndarray | None, ex: np.ndarray, ey: np.ndarray,
               et: np.ndarray, ep: np.ndarray, t_us: int, twist: np.ndarray | None, K: np.ndarray,
               prior: tuple[np.ndarray, np.ndarray] | None, gaps: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(pose, covariance) of the events (ideal pixels ``ex``, ``ey``, times ``et`` us, polarities ``ep``; ``gaps`` each
        one's time since its pixel's previous same-polarity event, us, for ``follower_crossings``, None = none) against the
        map points ``used`` (indices) starting from ``T_world_cam`` (the pose at ``t_us``); ``polarity`` (as ``used``)
        the polarity each point may fire (+1 / -1 / 0 both; None = any), ``twist`` the body twist per second (gtsam
        order), ``prior`` = (T_prior, information of the body tangent in squared pixels) or None. None when too few
        events associate or the system is singular."""
        events = (np.array(ex, np.float64), np.array(ey, np.float64), np.array(et, np.int64), np.array(ep, np.int8),
                  np.full(len(ex), np.int64(2) ** 62) if gaps is None else np.array(gaps, np.int64))  # None: each event a first
        return self._refine(T_world_cam, used, polarity, events, len(events[0]), t_us, twist, K, prior)

    def _refine(self, T_world_cam, used, polarity, events, n_events, t_us, twist, K, prior):
        """:meth:`refine` of the first ``n_events`` of ``events`` = (ex, ey, et, ep, eg), which it reorders in place
        (``eg``: each event's time since its pixel's previous same-polarity event, us)."""
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
        ex, ey, et, ep, eg = events
        assoc = np.empty(n_events, np.int64)
        # The associated events first, in order (the others took no part in the sums below).
        n = self.last_events = int(_associate_nearest(self.points, self._tangents, used, R_cw, t_cw, fx, fy, cx, cy,
                                                      float(c.association_radius_px), self._width, self._height, n_events,
                                                      ex, ey, et, ep, eg, pol, pts, tg, assoc))
        if n < int(c.min_events):
            return None
        H, b = np.zeros((6, 6)), np.zeros(6)
        sw, swr = np.empty(m), np.empty(m)
        info = None if prior is None else prior[1]
        leads = self._leads(used, T, xi, K)
        if self._passages is not None:  # this step's events count before its leads are set
            self._passages.update(n, assoc, used, pts, tg, eg, R_cw, t_cw, K, None if twist is None else xi)
            self._passages.add_leads(used, *leads)
        burst = self._burst if xi is _NO_TWIST else lead_terms(self._burst, c.lag, fx)  # no twist: no speeds
        edges = EdgeTerms(c.edge_clusters, self._clusters, used)
        args = (*leads, eg, burst, float(c.huber_px), float(c.gate_px), H, b, sw, swr, edges.swj, edges.pscale)
        out = (passes_python if edges.swj.size or edges.pscale.size else passes_compiled)(  # per-edge terms: between passes
            int(c.iterations), int(c.min_events), T, prior, edges, n, ex, ey, et, ep, assoc, pts, tg, fx, fy, cx, cy, xi, int(t_us), args)
        if out is None:
            return None
        pose_mat, n_used, swr2, R_cw, t_cw = out
        cov = np.empty((6, 6))
        if not spd_inverse(H + info if info is not None else H, cov):  # not positive definite
            return None
        self._last = (used, sw, swr, R_cw, t_cw, (fx, fy, cx, cy))
        return pose_mat, cov * ((swr2 / max(n_used - 6, 1)) * float(c.covariance_scale))

    def _leads(self, used: np.ndarray, T: np.ndarray, twist: np.ndarray | None = None,
               K: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(ON, OFF) lead of each point ``used`` (pixels), the grazing ones (see ``grazing_max_cos``) seen from the
        camera centre of ``T``; with ``covered_foot_off_lead_px``, ``twist`` (body, per second) and ``K``, the feet
        whose face narrows towards them at ``T`` take that on their OFF lead."""
        on, off = point_leads(used, self._crease, self._normals, self.points, self._plane_normals, T[:3, 3], self.config)
        c = self.config
        if self._rise is not None and twist is not None and K is not None and twist.shape[0] == 6:
            add_covered_foot_lead(off, used, self.points, self._tangents, self._rise, T, K, twist,
                                  float(c.covered_foot_max_width_px), float(c.covered_foot_off_lead_px))
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
        buffers = (np.empty(n_all), np.empty(n_all), np.empty(n_all, np.int64), np.empty(n_all, np.int8), np.empty(n_all, np.int64))
        table = calibration.undistortion_table if calibration.dist else _NO_TABLE
        n_kept = int(_kept_events(keep, events.x, events.y, events.t, events.p, table, *buffers[:4]))
        if self._pixel_last is not None:  # every event of the step moves its pixel's history, kept or not
            _pixel_gaps(keep, events.x, events.y, events.t, events.p, self._width, self._pixel_last, buffers[4])
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
            reg.T_world_cam, reg.covariance = combine_poses(reg.T_world_cam, reg.covariance, out[0], out[1], bool(c.combine_convex))
        else:
            reg.T_world_cam, reg.covariance = out
        return True


def event_registration_for(config, contour_map, tangents: np.ndarray, width: int, height: int,
                           pixel_mrad: float = 0.0) -> EventRegistration:
    """The :class:`EventRegistration` of a :class:`~evpose.tracker.config.TrackerConfig` over ``contour_map`` (its
    painted points and wall feet left out as ``config.event_registration`` says), ``tangents`` its unit edge directions,
    its pixel thresholds scaled for a sensor whose pixel subtends ``pixel_mrad`` (``1 / fx``; 0 = as configured, see
    ``EventRegistrationConfig.angle_reference_pixel_mrad``)."""
    from evpose.tracker.map_refinement import painted_points
    from evpose.tracker.wall_occlusion import wall_foot_mask

    er, vm = config.event_registration, config.visible_map
    skip = np.zeros(len(contour_map), np.bool_)
    if er.skip_painted:
        skip[painted_points(contour_map, float(config.map_refinement.max_curvature))] = True
    if er.skip_wall_feet:
        skip |= wall_foot_mask(contour_map, vm.wall_inward_m, vm.wall_radius_m, vm.wall_min_height_m, vm.wall_max_height_m)
    return EventRegistration(scaled_to_pixel(er, pixel_mrad), width, height, contour_map.points, tangents, contour_map.edge_normal, skip,
                             contour_map.plane_normal, contour_map.region_id)
