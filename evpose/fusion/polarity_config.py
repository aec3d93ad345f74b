"""Settings of the polarity prediction, its buffer zone and the event filter (:mod:`evpose.fusion.polarity`).

Its own module: the fields carry the measured history of each setting, which outgrew the filter's code.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class PolarityFilterConfig:
    """Parameters of the polarity prediction and its buffer zone."""

    enabled: bool = True
    """Predict polarities (False: every point uses both, i.e. plain STPE).

    Off in ``full``: no prediction and no ``T_align``, registration reads the combined field over the box, and the
    events' registration associates events of either polarity (the ego-motion filter is its own switch,
    ``ego_motion.enabled``). Session 31 (``full``, 2 s landing from ground truth, built map, 346x260): plain landing seeds
    0-11 4.625 mm on against 4.730 off (paired -0.11 +- 0.13 mm, 8 of 12 better on), textured landing seeds 0-2 5.18 /
    7.19 / 6.28 against 6.72 / 9.56 / 7.63 mm; its registration latency in ``full`` under ``event_filter``."""
    buffer_deg: float = field(default=20.0, metadata={"min": 0.0, "max": 89.0, "step": 0.5, "unit": "deg"})
    """Base half-width of the buffer zone around 90 deg, degrees.

    Session 14, ``stpe+filter`` with ``map_refinement.hold_out_filtered`` (no reopening, 5.5 ms lag at 240x180),
    2 s landing from ground truth, mean ATE of seeds 0-7 at 346x260 / 240x180: 20 -> 12.38 / 14.50 mm, 30 -> 12.21 /
    14.62 mm; every point both polarities (``min_image_speed_px_s`` 1e9) 11.60 / 14.57 mm (without the hold-out 12.71
    / 15.56 against 13.67 / 15.03 mm). The polarity choice costs ~0.8 mm at 346x260 and nothing at 240x180;
    ``reopen_contradicted_unfused`` (on) takes most of that back where the choice is contradicted."""
    flow_sigma_px_s: float = field(default=15.0, metadata={"min": 0.0, "max": 500.0, "step": 1.0, "unit": "px/s"})
    """Assumed uncertainty of the predicted image motion; widens the buffer by atan(sigma/speed), px/s."""
    max_buffer_deg: float = field(default=70.0, metadata={"min": 0.0, "max": 90.0, "step": 0.5, "unit": "deg"})
    """Upper limit of the adaptive buffer half-width, degrees."""
    min_image_speed_px_s: float = field(default=20.0, metadata={"min": 0.0, "max": 1000.0, "step": 1.0, "unit": "px/s"})
    """Below this image speed a point keeps both polarities, px/s."""
    min_gradient_visibility: float = field(default=0.2, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Minimum foreshortening of the projected edge normal (1 = parallel to the image plane) to trust its direction."""
    unknown_velocity_hold_updates: int = field(default=40, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """``full`` started without the initial velocity (``evpose track --init``, or ``initial_velocity_from_ground_truth``
    off): for this many first updates every point takes both polarities and the event filter (``T_align``) is off,
    updates (0 = never; a start from ground truth gives the velocity and is not affected).

    The first registrations give the fused velocity m/s wrong (a pose 3 cm off read over 5 ms is 6 m/s); a filter
    predicting polarities and aligning events with that motion keeps the events that agree with it, registration
    confirms it, and the track is lost (seed 2 at 346x260: the fused lateral velocity held at 5-6 m/s against 0, the
    pose off by 1 m after 0.15 s). Bench ``fusion.regimes`` ``cold`` (no velocity, pose 3 cm / 1 deg off), 346x260
    seeds 0-7, runs lost (ATE > 100 mm) factor graph / EKF: 0 (no hold) 2 / 3; 40 with only ``T_align`` off 1 / 1
    (seed 3; on the six seeds every run kept 16.10 / 16.01 mm); 40 (both polarities too) 1 / 1 (seed 5; the same six
    seeds 15.19 / 15.13 mm, the seven kept 15.43 / 15.38 mm); 240x180 seeds 0-7: 0: 2 / 0 lost (seeds 2, 3), 40: none
    (22.99 / 22.84 mm). With the pose given exactly (``cold_velocity``, 346x260, none lost either way) 0 -> 40: 6.185
    / 6.213 -> 6.127 / 6.119 mm (first 0.3 s 7.58 / 7.53 -> 6.96 / 6.93 mm). But the demos started the same way
    (``evpose track ... --init`` with the ground-truth pose at the first event, ``evpose eval --align none``, RMSE):
    ``landing`` 10.03 / 10.19 -> 11.67 / 11.70 mm, ``landing_fast`` 18.44 / 18.55 -> 18.35 / 18.55 mm: a lost track
    is metres, so it is on. 10 updates: ``landing`` 11.07 / 11.18 mm, ``cold`` the same runs lost (346x260 seed 5,
    240x180 none), the rest 15.68 / 15.67 and 23.00 / 23.10 mm (40: 15.43 / 15.38, 22.99 / 22.84)."""
    learn_min_votes: int = field(default=3, metadata={"min": 1, "max": 100, "step": 1, "unit": "votes"})
    """Net votes a point needs before a learned brightness sign is used."""
    learned_overrides_map: bool = True
    """A confident learned sign replaces the map's sign where they disagree (map signs from cloud albedo miss
    shading edges, e.g. creases between faces of one albedo: on the simulated landing scene only 69 % of them
    match the polarities the points trigger, while the learned signs are consistent over time)."""
    patch_radius_px: float = field(default=2.0, metadata={"min": 0.5, "max": 10.0, "step": 0.5, "unit": "px"})
    """Radius of a point's patch when classifying events or reading observed polarities, pixels."""
    event_filter: bool = True
    """Registration reads ``T_align`` (:mod:`evpose.fusion.aligned_surface`): in each used map point's patch only the
    predicted polarity's events, nothing outside the patches (False: per-point ON/OFF/combined fields over the whole box).

    Session 18, the issue's "the filter cuts registration latency by >= 40 %" (the paper: 20.11 -> 7.69 ms): not
    reachable by a filter that registers the map's points, whatever builds the field. Registration latency = CPU
    (thread time) of polarity prediction + ``T_align`` + field + registration per update, medians, 346x260 seeds 0-3,
    the variants alternated in one process, load 3-4.5; in ``stpe`` field + registration. Plain / textured landing:
    ``stpe`` 0.74 / 0.91 ms, ``stpe+filter`` 1.68 / 1.76 ms (2.28x / 1.95x; 10.5 / 63 % of the events removed). The
    floor: the prediction alone takes 0.27-0.29 ms and the registration stage ~0.3 ms before its points (0.32-0.35 ms
    for 148 points against 0.58-0.60 ms for 913, ``registration.max_points`` 150, seeds 0-1), so with 134 points
    ``stpe+filter`` still took 0.98-1.04 ms against ``stpe``'s 0.88-0.90 ms with 913; ``drop_empty_points`` (383-413
    points) 1.54-1.67 ms against 1.84-2.02 ms. The filter removes events, and registration's cost follows the points:
    the registration stage alone takes 0.58 / 0.61 ms against ``stpe``'s 0.49 / 0.56 ms, for 4 / 13 % fewer point
    linearisations (seed 0: 3.42 x 839 against 3.35 x 896 plain; linearisation kernel 0.25 against 0.23 ms).
    A grid-free filter was prototyped and not kept (``/tmp/s18/pointfield7/pfkern.py``): each point reads only its
    predicted polarity inside its own 4 px disk around its predicted projection (reopened when contradicted, no
    nearest-point ownership), the blurred TDF, gradient and curvature computed at the projection from the SP-TS
    maps (within 2e-7 of the field's values), so neither ``T_align``'s grid nor a field image is built before the
    pose: 1.68 -> 1.40 / 1.76 -> 1.58 ms, ATE 12.00 -> 11.77 / 23.84 -> 23.29 mm (its refiner read the plain time
    surface's field). But reading the field at the points serves ``stpe`` as well (0.74 -> 0.65 / 0.91 -> 0.76 ms,
    ATE unchanged to 0.001 mm), so within one design the filter still costs 2.16x / 2.07x ``stpe``; and the
    painted-edge refiner and the event labelling then need passes of their own after the pose (CPU per update 3.53
    -> 3.85 / 3.96 -> 4.61 ms). Turning this switch off (per-point
    polarity fields over the box, no reopening, no refiner) costs 12.00 -> 22.38 mm (plain landing).

    Session 21, where the filtered front end spends its CPU per update (346x260 seed 0, plain landing, medians; ``stpe``:
    field 0.18 + registration 0.40 = 0.58-0.60 ms): polarity prediction 0.20 ms (the IMU propagation to the update
    time and its fused state ~0.10, the per-point kernel 0.085), ``T_align`` 0.38-0.43 ms (marking 0.23, selecting
    0.11-0.13), field 0.14 ms, registration 0.43 ms (the same ~840 points x 3.4 linearisations as ``stpe``'s ~900 x
    3.35), labelling after the pose 0.09-0.10 ms. Registration alone exceeds 0.6 x ``stpe``'s whole front end (0.35
    ms), so no cheaper filter or field reaches the >= 40 % cut while registration's work follows the points.
    ``T_align``'s kernels now prefetch what they read next (:mod:`evpose.fusion.aligned_surface`, bit for bit the same outputs); this
    code against the code before, separate processes alternated, medians of the runs' medians (346x260 eight pairs,
    load 1.7-3.8; 240x180 four pairs): ``stpe+filter``'s ``stpe_latency`` 1.362 -> 1.280 ms (``T_align`` 0.432 ->
    0.384, labelling 0.101 -> 0.089) and 1.098 -> 1.055 ms; ``filter_stpe_latency_change_pct`` +126.7 -> +124.2 % and
    +114.2 -> +106.1 % (``stpe``'s code unchanged: 0.602 / 0.584 and 0.499 / 0.505 ms; per-run figures spread by
    +-30 points with the load, paired per round the front end gains a median 0.089 / 0.035 ms). Textured landing
    (346x260 seed 0, three pairs, 63.5 % of the events removed): 1.366 -> 1.263 ms against ``stpe``'s 0.679 ms,
    +101.2 -> +88.4 %; ATE unchanged everywhere (27.356 / 24.612 / 7.477 mm there). Tried, not kept (figures
    in :mod:`evpose.fusion.aligned_field` and :mod:`evpose.fusion.aligned_surface`): the field blurred only in the tiles
    near the patches (0.155 -> 0.227 ms), branch-free or per-row-run marking, and a branch-free selecting pass
    (in a run, three alternated pairs: 0.122 / 0.112 / 0.157 against 0.129 / 0.115 / 0.138 ms).

    Session 30, the same question again (the issue's -40 %, i.e. ``stpe+filter`` <= 0.6 x ``stpe``), CPU (thread
    time) per update, 346x260 seed 0, the modes alternated in one process (3-4 rounds, load 4-5.4; medians; script
    ``/tmp/s30/lat30/lat.py``, per-kernel wrappers ``filtprof.py`` / ``regprof.py``). Plain landing: ``stpe`` 0.67-0.86
    ms (field 0.20-0.27, registration 0.44-0.57), ``stpe+filter`` 1.58-1.82 ms (2.05-2.58x; to the pose 1.44-1.67):
    prediction 0.26-0.30 (IMU propagation 0.10-0.12, per-point kernel 0.09-0.10, the rest Python), ``T_align``
    0.45-0.48 (marking 0.23-0.27, selecting 0.13-0.16, the rest Python), field 0.18-0.20 (scatter 0.074, blur and
    gradients 0.094-0.10), registration 0.53-0.64, labelling after the pose 0.12-0.14 (its kernel 0.035). Textured
    landing (63.5 % of the events removed): ``stpe`` 0.749, ``stpe+filter`` 1.833 ms (2.45x). The floor of any filter
    that registers the map's points is its field and registration alone: 0.71-0.84 ms, 1.07-1.11x ``stpe``'s whole
    front end (textured 0.86-1.09x over three sets of rounds), because the fusion the prediction needs runs beside the registration and its cache
    footprint slows the registration: ``stpe+filter`` with ``enabled`` off (the fusion beside, no filter, the same
    registration as ``stpe`` bit for bit) costs 0.756 against ``stpe``'s 0.669 ms. Nor does the filter's choice of
    points cut the registration: ``drop_empty_points`` (383 of 857 points; ATE 12.54 -> 13.16 mm) 0.630 -> 0.575 ms (its linearisation 71 ->
    46 us for 3.4 -> 3.9 linearisations; per call ~25 us whatever the points), ``register_min_normal_speed_px_s`` 20
    (778 points) none, and both cost accuracy (below). So the -40 % stays out of reach; what session 30 cut:
    the prediction's IMU propagation before the pose (``unfused_latest_motion``, -0.10 ms, same ATE). The bench's
    ``ablation`` now reports the floor (``filter_free_floor_change_pct``) and the change to the pose
    (``filter_stpe_latency_to_pose_change_pct``).

    Session 31, the claim read in ``full``, the filter on against ``enabled`` off (where the events registered at their
    own timestamps, whose cost follows the events, give the pose too; bench ``fusion.full_filter_cost``,
    :mod:`evpose.bench.filter_registration_cost`, which has the table; 346x260 seed 0, CPU per update, medians of 4
    alternated rounds): every stage up to the pose (prediction, ``T_align``, field, field registration, events'
    registration) 2.048 against 1.516 ms on the textured landing (+35 %, ``full_filter_registration_latency_change_pct``),
    1.850 against 1.204 on the plain one (+54 %; seed 1 +46 %). The field gets 29-48 % cheaper, the two registrations
    stay level (+2 / +10 %; the events' alone -1 / +2 %): the events ``T_align`` removes are off the map's edges, where
    the events' association (2 px) takes none either, so the filter changes the events that stage registers by 1-3 %.
    Not met in this reading either; the filter's own prediction and ``T_align`` (0.59-0.65 ms) exceed the whole field."""
    drop_empty_points: bool = False
    """Registration skips map points whose ``T_align`` patch shows no accepted event younger than
    ``empty_after_eta`` (50-60 % of the used points on the simulated landing); points whose patch shows only the
    other polarity are first reopened (``reopen_contradicted``): they are the wrongly predicted ones, whose edge
    registration needs (dropping them too cost ``stpe+filter`` 34 -> 91 mm ATE). Dropped points still count in the
    registration's residual variance (:meth:`MapPolaritySelector.registration_covariance`) and still learn signs.
    Measured, simulated landing seeds 0-3 mean, 346x260 / 240x180: ``full`` 13.6 / 15.1 mm, 0.172 / 0.194 deg
    against 13.5 / 15.5 mm, 0.171 / 0.198 deg off (seed 0: 15.4 / 19.8 mm, 0.228 / 0.295 deg against 16.6 / 20.7
    mm, 0.241 / 0.312 deg); 4 s demos: landing 17.1 vs 17.4 mm (0 vs 50 IMU-bridged updates), fast 23.6 vs 22.3 mm,
    dynamic 34.2 vs 34.9 mm; but ``stpe+filter`` 33.1 / 39.0 against 30.5 / 35.8 mm. Registration wall time fell
    only 16 % (0.70 -> 0.59 ms median, paired, load 2.1) for 54 % fewer points, the filter's own time rose
    0.15 ms: the registration's per-iteration overhead, not its points, dominates. So off by default. Session 10
    (``stpe+filter``, seeds 0-3, 346x260 / 240x180): 14.90 / 20.58 mm against 14.78 / 21.70;
    ``register_to_map`` CPU 1.54 against 1.67 ms median (see ``register_min_normal_speed_px_s``). Session 14 (with
    ``map_refinement.hold_out_filtered`` and reopening, 5.5 ms lag at 240x180; seeds 0-7 at 346x260 / 240x180):
    12.38 / 15.76 mm against 11.76 / 14.75 mm off; CPU per update (seed 0, 346x260, three alternated runs, load ~18)
    registration 0.46 -> 0.40 ms, the filter's front end (field, prediction, ``T_align``, registration) 1.54 -> 1.50 ms.
    Session 18 (346x260 seeds 0-3, ``stpe+filter``): 12.81 against 12.00 mm; see ``event_filter`` for its latency."""
    reopen_contradicted: bool = False
    """``T_align`` accepts both polarities in the patch of a single-polarity point that shows no event of its predicted
    polarity younger than ``empty_after_eta`` but does of the other: the events contradict the prediction (a wrong
    sign or edge normal: 8-10 % of the single-polarity predictions on the simulated landing), and reading the predicted
    polarity only would hide the point's own edge. What makes ``drop_empty_points`` work (see there). Alone it does
    not pay on the simulated landing (seeds 0-3 mean, 346x260 / 240x180): ``stpe+filter`` 30.4 / 34.6 mm against
    30.5 / 35.8 mm off (``stpe`` 30.0 / 34.9), ``full`` 14.3 / 16.0 against 13.5 / 15.5 mm. Session 10 (2 s landing
    from ground truth, mean ATE of seeds 0-3, 346x260 / 240x180): ``stpe+filter`` 14.78 / 21.70 -> 13.80 / 20.76 mm
    (seeds 4-7: 12.56 / 19.49 -> 11.75 / 18.68 mm; ``stpe`` 12.40 / 18.47 and 11.66 / 20.12), but ``full`` 7.77 ->
    8.21 mm at 346x260 (12.56 against 13.27 mm on seed 0 at 240x180): see ``reopen_contradicted_unfused``."""
    register_min_normal_speed_px_s: float = field(default=0.0, metadata={"min": 0.0, "max": 500.0, "step": 1.0, "unit": "px/s"})
    """Registration skips map points whose predicted image motion across their edge (the image speed times the
    cosine of the angle between projected edge normal and motion) is below this: they fire almost no events, so
    their patch shows stale ones (0 = register all), px/s. They stay in ``T_align`` and keep learning signs, and do
    not count in the registration covariance (their field is not the "never fired" one ``drop_empty_points`` adds).
    Only with the event filter (``T_align``).

    Off by default, measured (session 10, ``stpe+filter``, 2 s landing from ground truth, mean ATE of seeds 0-3 at
    346x260 / 240x180; 14.78 / 21.70 mm with 0): 40 px/s (about 16 % of the points, nearly all in the buffer zone)
    15.89 / 22.36 mm, 100 px/s 18.67 mm at 346x260 (seeds 0-2, against 14.66). A point whose edge moves along itself
    still holds the cross-flow direction with the events its edge fired earlier (leaving out the whole buffer zone
    in ``full`` cost 7.8 -> 1215 mm, session 9), and registration time hardly falls with the points: CPU time of
    ``register_to_map`` per update (seed 0, 346x260, six configurations stepped alternately in one process, load
    29-38, median / p95) ``stpe`` 1.80 / 2.92 ms, ``stpe+filter`` 1.67 / 2.47, with 40 px/s (756 of 898 points)
    1.65 / 2.47, ``drop_empty_points`` (421 of 898) 1.54 / 2.32, ``registration.max_points`` 500 (471 points) 1.42 /
    2.20 ms: the per-call cost, not the points, dominates, so no choice of points reaches the paper's 40 % cut.
    Session 30 (``stpe+filter`` mean ATE, 2 s landing seeds 0-7 at 346x260 / 240x180, textured landing seed 0; 0:
    11.760 / 14.090, 25.278 mm): 10 px/s 12.020 / 14.139, 24.549 mm; 20 px/s (778 of 857 points) 12.078 / 14.278,
    24.743 mm; 30 px/s 12.544 / 14.466, 25.779 mm: worse on the plain landing at every threshold, so still off."""
    reopen_contradicted_unfused: bool = True
    """As ``reopen_contradicted``, but only where the pose is not fused with the IMU (``stpe+filter``: ``full`` is left
    as it is, where reopening costs, see there).

    Session 10, ``stpe+filter``, 2 s landing from ground truth, mean ATE at 346x260 / 240x180: seeds 0-3 14.78 /
    21.70 -> 13.80 / 20.76 mm, seeds 4-7 12.56 / 19.49 -> 11.75 / 18.68 mm (``stpe`` 12.40 / 18.47, 11.66 / 20.12);
    events removed 13.1 -> 9.5 % (346x260). Why ``stpe+filter`` trails ``stpe`` on this scene: with every point
    shown both polarities in its patch (``buffer_deg`` 89) it scores 13.79 / 20.42 mm, as with this switch, so the
    polarity choice costs ~1 mm through the contradicted points and the rest is the patches' and the painted points'
    share (``map_refinement.register_after_updates`` holds painted points out only in ``stpe``); larger patches
    (10 px, all both) did not help (13.55 / 12.95 against 12.79 / 12.74 mm on seeds 0 / 1 at 346x260). Left off then:
    on the textured landing (seed 0, 346x260; ``stpe`` 27.36, ``full`` 10.08 mm, 64 % of the events removed) it
    costs ``stpe+filter`` 22.66 -> 23.71 mm, where the filter's point is to hide the texture's events.

    On since session 14, with ``map_refinement.hold_out_filtered`` (mean ATE of seeds 0-7 at 346x260 / 240x180):
    12.38 / 14.17 -> 11.76 / 14.12 mm with ``edge_offsets.stpe_filter_field_lag_ms`` 6.0 (with 5.5: 14.50 -> 14.75 mm
    at 240x180); textured landing 24.60 -> 24.61 mm. Its check of the other polarity now runs in the selecting pass
    (:func:`~evpose.fusion.aligned_surface_kernels._select_times_reopening`), not in a pass of its own."""
    unfused_latest_motion: bool = True
    """In ``stpe+filter`` (where the fusion runs beside the registration, not as its prediction) take the motion the
    prediction needs from the gyro at the update time less the latest fused gyro bias, and the latest fused velocity
    (one update old) moved on to the update time by one accelerometer step (the latest fused attitude and accelerometer
    bias, gravity), instead of propagating the fused state with the IMU to the update time: that propagation then runs
    once, in the fusion's update after the pose is out, not in the front end (``full`` predicts its pose by that
    propagation anyway and reuses it).

    On since session 30 (with the accelerometer step). Mean ATE of ``stpe+filter``, 2 s landing from ground truth,
    seeds 0-7 / held-out 8-15 (``/tmp/s30/lat30/run.py``, ``MODE=stpe+filter``): 346x260 11.760 -> 11.736 / 12.415 ->
    12.415 mm, 240x180 14.090 -> 14.090 / 16.112 -> 16.127 mm (30 of the 32 runs the same to 0.01 mm; seed 5 at
    346x260 10.94 against 11.13, seed 8 at 240x180 13.61 against 13.50), textured landing seed 0 25.278 -> 25.279 mm.
    CPU per update (346x260 seed 0, the three runs alternated in one process over 4 rounds, load 4.5-5.4, medians):
    polarity prediction 0.289 -> 0.187 ms, the filter's front end (field, prediction, ``T_align``, registration,
    labelling) 1.760 -> 1.640 ms (p95 2.544 -> 2.348), to the pose (without the labelling) 1.612 -> 1.488 ms (p95
    2.391 -> 2.185), ``stpe`` 0.858 ms (``/tmp/s30/lat30/lat.py``); textured landing, 5 rounds at load 4.9-6.4:
    prediction 0.257 -> 0.162 ms, front end 1.571 -> 1.409 ms (p95 2.102 -> 1.959; faster in each round), to the pose
    1.400 -> 1.259 ms, ``stpe`` 0.770 ms (3 more rounds: 1.660 -> 1.673 ms, the rounds spread by +-0.1 ms). The demos
    (``evpose track --mode stpe+filter``, ``evpose eval --align none``): ``landing`` and ``landing_fast`` the same
    trajectories, ``landing_dynamic`` within 0.001 mm; ``full`` untouched (demo ``1c3f8d90bee2efe8``). The 3 s landings
    (seeds 0-3) say nothing here: ``stpe``, and ``stpe+filter`` either way, are ~100 mm off after 0.25 s and metres
    by 3 s (``/tmp/s30/lat30/trace3s.py``; run.py's means over the OK updates 120.5 / 126.2 mm, seeds 1-2 the same). The latest fused velocity as it is, without the
    step (the option until session 30): 11.793 / 14.201 mm on seeds 0-7 (7 of the 7 runs that changed worse; session
    14: 11.79 / 14.21 against 11.76 / 14.12 mm), textured 25.198 mm. For comparison, the motion taken from
    ``stpe+filter``'s own constant-velocity filter (its twist; no IMU at all) gave 11.76 / 13.94 mm (session 14), and
    at 190 / 210 Hz (``rate_hz``) 12.06 / 11.78 and 14.05 / 14.30 mm against 11.77 / 11.82 and 14.34 / 14.22 mm with
    the IMU's: the filter's accuracy does not hinge on the IMU's motion."""
    empty_after_eta: float = field(default=3.0, metadata={"min": 0.5, "max": 12.0, "step": 0.5, "unit": "eta"})
    """A patch whose newest accepted event is older than this many time-surface constants counts as empty (TDF > 0.95 at 3), eta."""
    align_patch_radius_px: float = field(default=4.0, metadata={"min": 1.0, "max": 30.0, "step": 0.5, "unit": "px"})
    """Radius of the patch around each predicted projection that ``T_align`` keeps; must cover the prediction error
    plus the TDF blur (points whose true edge lies outside it see no events). Full mode on the simulated landing
    346x260 scored alike from 3 to 8 px (20.7 / 21.5 / 21.3 mm ATE at 3 / 5 / 8); the cost grows with its square.
    ``stpe+filter`` (no fused prediction, larger errors) gains from 8 px: 77.0 -> 70.4 mm at 346x260 and
    99.3 -> 60.5 mm at 240x180, while full mode stays at 17.8 / 19.9 mm but pays ~0.7 ms per update and the
    share of events removed falls from 17 % to 10 %; so 4 stays the default. 3 px (session 8, seed 0, 346x260) cuts
    ``T_align``'s composition by 0.06-0.23 ms but costs ``stpe+filter`` 23.82 -> 24.08 mm (textured landing) and
    15.15 -> 15.85 mm (plain), ``full`` 11.38 -> 12.09 mm on the plain landing (9.38 vs 10.18 mm textured). Session 9,
    ``stpe+filter`` seeds 0-3 (346x260 / 240x180): 4 / 6 / 8 px 15.77 / 23.37, 16.25 / 23.54, 16.12 / 23.25 mm.
    Session 17 (346x260 seeds 0-3, mean ATE, 4 -> 3 px): plain landing ``stpe+filter`` 12.00 -> 13.40, ``full`` 6.38 ->
    6.70 mm; textured 23.84 -> 22.83 and 9.12 -> 8.00 mm; events removed 10.5 -> 15.6 % (plain), 63.5 -> 66.6 %
    (textured); ``T_align`` composition -0.14 / -0.16 ms CPU, but ``stpe+filter``'s registration latency (prediction,
    composition, field, registration) stays 2.07-2.20x / 1.83x ``stpe``'s (plain / textured). Session 42 (lat42,
    ``/tmp/s42/lat42/``), 3.5 as a speed lever: CPU per update of ``full`` at 346x260 (seed 0, paired in one process,
    ``pairstep.py``, load ~13) -0.098 +- 0.022 ms mean (-0.056 median, ~2 %); ATE (CLI, 240x180 2 s, paired against
    main's defaults): nominal seeds 0-23 4.770 -> 4.773 mm (+0.003 +- 0.041, 12 of 24 better), flights 1-12 14.187 ->
    14.136 (-0.051 +- 0.123, 6 of 12), flights 13-24 14.906 -> 15.260 (+0.354 +- 0.200, 1 of 12); with
    ``registration.max_iterations`` 2 too (-0.173 +- 0.019 ms mean): 4.740 (-0.029 +- 0.048, 15 of 24), 14.162 (-0.025
    +- 0.159, 5 of 12), 15.348 (+0.442 +- 0.371, 4 of 12): not kept, pixels."""
