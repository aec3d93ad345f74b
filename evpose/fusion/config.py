"""Configuration of the IMU fusion backends (factor graph, error-state EKF, IMU-only dead reckoning)."""

from __future__ import annotations

from dataclasses import dataclass, field

from evpose.fusion.choices import FusionBackend, RegistrationErrorModel, RobustLoss  # noqa: F401  (re-exported)


@dataclass
class FusionConfig:
    """Noise model and graph shape of the IMU fusion.

    Noise densities are continuous-time (Kalibr/Allan-deviation convention): the
    discrete standard deviation of one sample is ``density * sqrt(rate)``.
    """

    backend: FusionBackend = FusionBackend.FACTOR_GRAPH
    """Estimator that fuses registrations with the IMU."""
    accel_noise_density: float = field(default=2.0e-3, metadata={"min": 1e-5, "max": 1.0, "step": 1e-4, "unit": "m/s^2/sqrt(Hz)"})
    """Accelerometer white-noise density, m/s^2/sqrt(Hz)."""
    gyro_noise_density: float = field(default=1.7e-4, metadata={"min": 1e-6, "max": 0.1, "step": 1e-5, "unit": "rad/s/sqrt(Hz)"})
    """Gyroscope white-noise density, rad/s/sqrt(Hz)."""
    accel_bias_random_walk: float = field(default=3.0e-3, metadata={"min": 1e-7, "max": 1.0, "step": 1e-5, "unit": "m/s^3/sqrt(Hz)"})
    """Accelerometer bias random-walk density, m/s^3/sqrt(Hz). (The simulator's is 3e-4: the same figures to 0.01 mm.)
    Far larger values let the bias absorb slowly varying acceleration errors (gravity leaking through the tilt
    error): 0.3 gave seeds 0-3 (closed loop, 346x260 / 240x180) 8.4 / 9.0 mm against 9.1 / 9.6 (EKF likewise 8.3 /
    9.1), 0.1 / 0.2 / 0.5 8.9-8.3 / 9.2-9.6 mm, but the 4 s demos 15.5 / 25.3 / 20.5 mm against 16.0 / 23.2 / 21.0
    (landing / fast / dynamic): not kept."""
    gyro_bias_random_walk: float = field(default=2.0e-5, metadata={"min": 1e-8, "max": 0.1, "step": 1e-6, "unit": "rad/s^2/sqrt(Hz)"})
    """Gyroscope bias random-walk density, rad/s^2/sqrt(Hz) (the simulator's). Larger values let the graph forget the
    bias error it learns from the registrations' start-up swing (see ``registration_startup_s``). Session 33, ``full``,
    240x180 2 s landing, the CLI path (``/tmp/s33/gyro33/run.sh``, ``cmp.py``), paired against 2e-5 (seeds 0-23
    5.568 mm): 2e-4 5.580 (+0.011 +- 0.020, 11 of 24 better), 1e-3 5.523 (-0.046 +- 0.031, 16 of 24), held-out seeds
    24-47 6.091 -> 6.066 (-0.025 +- 0.041, 13 of 24); with ``registration_startup_s`` 0.5 seeds 0-23 5.507: not
    changed. Session 42 (tune42, other flights, see ``init_sigma_gyro_bias``): 1e-3 on 240x180 flights 1-12 14.187 ->
    14.121 mm (-0.067 +- 0.093, 6 of 12 better): a bias free to follow the ridge error does not stop the fused tilt
    drifting past the registrations either."""
    gravity: float = field(default=9.81, metadata={"min": 9.7, "max": 9.9, "step": 0.001, "unit": "m/s^2"})
    """Gravity magnitude along world -z (z-up world), m/s^2."""
    integration_sigma: float = field(default=1.0e-4, metadata={"min": 0.0, "max": 0.1, "step": 1e-5, "unit": "m"})
    """Integration (discretisation) noise of preintegration, standard deviation per sqrt(s) (gtsam's integrationCovariance = sigma^2 I), m."""
    registration_loss: RobustLoss = RobustLoss.HUBER
    """Robust kernel on the registration pose factor."""
    registration_loss_scale: float = field(default=3.0, metadata={"min": 0.1, "max": 20.0, "step": 0.1, "unit": "sigma"})
    """Threshold of the robust kernel on the whitened residual (in standard deviations). Session 13: on the
    simulated landings the graph's kernel never engages (with the covariance scaled by 30 the residuals stay within
    1 sigma): 1 (346x260 seeds 0-11) or no robust loss (346x260 and 240x180 seeds 0-7) gave the same
    figures to 0.001 mm / 0.0001 deg, so it is no difference between the graph and the EKF (which weighs the innovation instead)."""
    registration_default_sigma_rot: float = field(default=0.01, metadata={"min": 1e-5, "max": 0.5, "step": 1e-4, "unit": "rad"})
    """Rotation sigma used when a registration comes without covariance, rad."""
    registration_default_sigma_trans: float = field(default=0.01, metadata={"min": 1e-5, "max": 1.0, "step": 1e-4, "unit": "m"})
    """Translation sigma used when a registration comes without covariance, m."""
    registration_covariance_scale: float = field(default=30.0, metadata={"min": 1.0, "max": 10000.0, "step": 1.0, "unit": "ratio"})
    """Factor on the registration covariance before fusion. Registrations at a few hundred Hz share most of their
    events (the SP-TS remembers ~``12 eta`` = 120 ms, 24 updates at 200 Hz) and the same map, so their errors are
    correlated over many updates (on the simulated landing: 10 mm wander, 3 mm from one update to the next) and
    each carries only a fraction of the information its own covariance claims; scaling by about the number of
    updates that share events lets the IMU smooth the wander. Measured (full mode, ATE mm for 1 / 30 / 300):
    landing 346x260 18.0 / 14.6 / 11.9, 240x180 28.3 / 23.6 / 22.2; fast landing 240x180 22.5 / 24.7 / 30.8
    (rotation better at every scale). With white registration noise (bench ``fusion.backends``) 1 is optimal.
    Statistically (bench ``fusion.registration_wander``): the mean of N registrations has the variance of
    N / tau_int independent ones, tau_int the errors' integrated autocorrelation time (50-63 updates on the landing,
    31-62 on the bundled demos) while the covariance is about 1.5-2x conservative (NEES median 2.4-3.6 against
    5.35), so tau_int / 2 ~ 30 is the consistent scale. Larger scales help the 2 s benchmark (300: 13.3 mm, 1000:
    12.0 mm at 346x260, replayed) but not the 4 s demo landing (25.1 / 54.2 / 74.1 mm at 30 / 300 / 1000). Other
    shapes, seeds 0-3 replayed (9.1 / 9.6 mm at 346x260 / 240x180 with this scale): the errors' variance times
    autocorrelation time per eigen-direction of the covariance is ~3-30x the covariance in its best-constrained
    direction but only ~0.1-3x in the tilt/shift directions; a covariance calibrated that way gave 9.4-9.6 /
    10.1-10.3 mm, the tilt/shift directions inflated 3x 9.0 / 9.5 mm; an explicit registration-offset state
    (world-frame Pose3 per state, random-walk chain plus a stationary prior: a Gauss-Markov bias) 8.7 / 9.5-9.7 mm
    at best. The errors that reach the output are slower than ~0.5 s (:func:`~evpose.fusion.replay.error_band_study`),
    which no weighting can tell from motion online. Session 9, closed loop, seeds 0-3 (7.78 / 9.40 mm with this
    covariance): the 2 least-constrained directions of its correlation matrix inflated 3 / 10 / 100x 7.90 / 8.63,
    8.39 / 8.54, 8.92 / 9.60 mm (at 3x the EKF got 8.39 mm at 240x180, better than the graph); the rotation block
    scaled 3 / 0.3x 12.3 / 9.8, 10.6 / 12.1 mm. Bounds on the same registrations (replayed): the simulator's true
    biases at the start, held tight, 5.39 / 7.27 mm, and the rotation held exact too 5.37 / 7.69 mm; each state's
    estimate 8 / 20 / 40 / 100 updates later (a lagged output) 7.36 / 6.70 / 5.89 / 4.99, 9.16 / 8.73 / 8.26 /
    7.87 mm: even the offline smoother (4.3 / 7.3 mm) misses 5 mm at 240x180, so the target needs better
    registrations (with the simulator's true edges as the map, ``full`` 7.30 / 8.80 mm: not the map's). Session 12,
    the field's registrations combined with the events' (:mod:`evpose.tracker.event_registration`, which scales its
    own covariance; seeds 0-3 6.38 / 7.25 mm): 10 / 100 gave 6.57 / 8.04, 6.37 / 7.80 mm. Session 14, 240x180 seeds 0-3 with
    ``init_sigma_acc_bias_vertical`` 0.5 (6.74 mm): 20 / 50 gave 6.85 / 6.91 mm. Session 18, seeds 0-7 (240x180 /
    346x260 7.325 / 5.30 mm), the 2 least-constrained directions of the correlation matrix inflated 10x 7.92 / 6.08,
    3x 7.48 mm (240x180). Session 20 (``/tmp/s20/res7/``), ``full``, 2 s landing, mean ATE mm / ARE deg: 240x180 seeds
    0-7 at 30 / 15 / 10 / 5 7.325 / 6.753 / 6.539 / 6.177 mm (ARE 0.0802 / 0.0756 / 0.0731 / 0.0728), held-out seeds
    8-11 at 30 / 10 / 5 6.855 / 6.195 / 6.246 mm (ARE 0.0744 / 0.0743 / 0.0731); 346x260 seeds 0-7 at 30 / 15 / 10 5.305
    / 5.288 / 5.237 mm (ARE 0.0589 / 0.0618 / 0.0618); but the 3 s landing at 240x180 (seeds 0-3, ~150 of its updates
    lost in every run) 18.91 -> 20.01 mm at 10 (per seed 23.41 18.50 13.80 19.93 -> 14.74 22.71 19.77 22.81), and
    the 346x260 demos got worse with smaller scales before (above). Not changed. The registrations' own errors
    against this covariance (``diag.py``, ``tau.py``; every update of seeds 0-7, unscaled): NEES mean 0.73 at 240x180
    and 1.05 at 346x260 (6 expected), integrated autocorrelation time of the whitened errors 17-61 updates at both, so
    the scale consistent with them would be ~6 / ~8 (per whitened component 0.8-18.5 / 1.6-21.3); the registrations'
    echo of the prediction (see :mod:`evpose.tracker.event_registration`, session 20) makes their errors look smaller
    than what they measure, so that is a lower bound. Session 20 (``/tmp/s20/cov7/``, with
    ``RegistrationConfig.fused_prior_reference_pixel_mrad``), mean ATE mm (ARE deg) at 30 -> 20 -> 10: 2 s landing
    240x180 seeds 0-7 7.007 (0.0771) -> 6.629 (0.0735) -> 6.487 (0.0777), held-out 8-11 6.807 (0.0796) -> 6.735
    (0.0767) at 10; 346x260 seeds 0-7 5.302 (0.0592) -> 5.356 (0.0607) -> 5.237 (0.0618), held-out 8-11 4.601 (0.0451)
    -> 4.404 (0.0435) at 10; 3 s landing seeds 0-3 346x260 12.155 -> 12.685 -> 13.116, 240x180 18.638 -> 19.317 ->
    22.014; the demos (``evpose track`` + ``evpose eval --align none``) at 10: landing 9.953 -> 7.811, landing_fast
    18.560 -> 18.988, landing_dynamic 10.435 -> 11.108 (ARE 0.108 -> 0.080, 0.171 -> 0.187, 0.112 -> 0.114). On the 3 s
    landing (346x260 seed 1, ``errprof.py``) the extra error at 10 builds up over 0.5-1.4 s while the registrations are
    healthy (a fifth to a third of the points on recent events, 800-1800 events per update), and stays after the turn.
    Scaling up only the less trustworthy registrations (scale 10 otherwise; 3 s, 346x260, seeds 0-3) made that worse,
    not better: the covariance times ``0.15 / share`` below an inlier share of 0.15 (the 2 s landings never go below
    0.17, the turn 0.04-0.12) 13.857, scale 30 for the 24 registrations after a loss 14.010, times ``1000 * (pixels /
    346x260's) / events`` (at most 3) 14.561 mm; a floor (``registration_min_sigma`` 1e-3 / 2e-3) 12.991 / 12.519
    there, but 2e-3 gave 5.374 mm on the 2 s 346x260 seeds 0-7. None of these signals tells the 3 s landing's slow
    error from the 2 s landing's: not changed, ratio. Session 42 (tune42, other flights, see ``init_sigma_gyro_bias``),
    15 with ``init_sigma_gyro_bias`` 0.005, paired against main's defaults: 240x180 flights 1-12 14.187 -> 13.214 mm
    (-0.97 +- 0.32, 9 of 12 better; against 0.005 alone +0.80 +- 0.21), the nominal flight's seeds 0-23 4.770 ->
    4.887 (+0.12 +- 0.10, 12 of 24; against 0.005 alone -0.48 +- 0.15, 16 of 24), held-out flights 13-24 -0.75 +-
    0.28 (8 of 12), 346x260 -0.72 +- 0.35 (10 of 13): but the demos (``demo.sh``) ``landing`` 6.554 -> 8.302,
    ``landing_fast`` 9.035 -> 9.244, ``landing_dynamic`` 6.011 -> 6.105 mm (0.007 alone: 7.904 / 9.204 / 6.078): not
    changed."""
    registration_error_model: RegistrationErrorModel = RegistrationErrorModel.WHITE
    """Time structure of the registration errors the factor graph assumes (the EKF always takes them as white).
    Session 10, closed loop, ATE mm 346x260 / 240x180 (white: seeds 0-3 7.77 / 9.40, seeds 4-7 7.95 / 11.37, demo
    landing 15.8 with RTE 0.28, RMSE): ``ar1_whitened`` at (rho, ``registration_ar_covariance_scale``) (0.92, 1) 7.21 /
    9.23, (0.92, 0.5) 7.26 / 8.63, (0.92, 0.3) 7.62 / 8.39, (0.95, 1) 6.98 / 8.74, (0.95, 0.5) 7.27 / 8.29 on seeds
    0-3, but seeds 4-7 (0.95, 0.5) 7.95 / 11.46, (0.95, 1) 8.78 / 12.56 (ARE worse: 0.096 / 0.120 deg against
    0.081 / 0.103), and the demo landing (0.95, 0.5) 27.5 mm with RTE 1.68 mm: the between factors hand the
    registrations' update-to-update jitter (~3 mm) to the estimate, which pure AR(1) errors would not have (the
    errors are a slow wander plus white jitter, which one-lag whitening amplifies). ``ar1_between`` (the newest state
    held with the interior weight) at scale 10 / 3 / 1 / 0.3 (rho 0.92): 9.90 / 13.81, 8.34 / 11.10, 7.73 / 9.73,
    8.19 / 9.06 on seeds 0-3. ``ar1_whitened`` with the between factor inflated (rho 0.95;
    (``registration_ar_covariance_scale``, ``registration_ar_between_scale``)): (0.5, 3) 6.94 / 8.95, (0.5, 10)
    6.74 / 9.33, (0.2, 10) 7.07 / 8.78 on seeds 0-3; seeds 4-7 (0.5, 3) 8.37 / 12.35, (0.2, 10) 7.64 / 11.25 (ARE
    0.084 / 0.107 deg), but the demo landing 28.4 / 20.7 mm (RTE 1.56 / 1.46 mm). Not kept: white."""
    registration_ar_rho: float = field(default=0.92, metadata={"min": 0.0, "max": 0.999, "step": 0.01, "unit": "ratio"})
    """AR(1) coefficient from one registration's error to the next (per update) for the AR(1) error models, ratio."""
    registration_ar_covariance_scale: float = field(default=10.0, metadata={"min": 0.01, "max": 10000.0, "step": 0.1, "unit": "ratio"})
    """With an AR(1) error model: the factor on the registration covariance giving the innovation covariance
    (replaces ``registration_covariance_scale``), ratio."""
    registration_ar_between_scale: float = field(default=1.0, metadata={"min": 0.01, "max": 10000.0, "step": 0.1, "unit": "ratio"})
    """With an AR(1) error model: an extra factor on the between factor's covariance (1: the exact AR(1) whitening;
    larger: the relative registrations carry jitter as well), ratio."""
    registration_min_sigma: float = field(default=1.0e-4, metadata={"min": 0.0, "max": 0.1, "step": 1e-5, "unit": "rad|m"})
    """Floor added in quadrature to the registration covariance diagonal so an over-confident registration cannot freeze the filter, rad or m."""
    constant_velocity_sigma: float = field(default=2.0, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "m/s/sqrt(s)"})
    """Weak constant-velocity prior between consecutive states: velocity change sigma per sqrt(s), m/s/sqrt(s).
    The one input the graph takes that the EKF does not; through the IMU factor's specific force it weighs on the
    tilt and the accelerometer bias, not only on the velocity. Session 13, closed loop, ATE mm / ARE deg per set
    (346x260 seeds 0-3, 4-7, 8-11; 240x180 the same) and the mean of the 24 runs, with 2: 6.38 / 5.91 / 6.15,
    7.25 / 8.48 / 8.43 mm, 0.0655 / 0.0676 / 0.0637, 0.0760 / 0.0875 / 0.0887 deg, mean 7.102 mm / 0.0748 deg
    (EKF 7.120 / 0.0755). 0.5: 6.16 / 5.89 / 6.30, 7.11 / 9.14 / 9.22 mm, mean 7.305 / 0.0740; 1: 6.49 / 5.84 / 6.09,
    7.49 / 8.59 / 8.54, mean 7.174 / 0.0753; 4: 6.44 / 5.96 / 6.07, 7.28 / 8.53 / 8.32, mean 7.098 / 0.0752; 100 (no
    prior, as the EKF): 6.40 / 6.08 / 5.99, 7.32 / 8.57 / 8.26, mean 7.103 / 0.0758 (ARE worse in all six sets). No
    trend: kept. The 2 s landing's true acceleration is 0.7 m/s^2 RMS (velocity change 3.5 mm/s per 5 ms update)
    but the 4 s demo's 3.7 m/s^2 (37 mm/s per update), so a tighter prior would fit the short benchmark only."""
    window_states: int = field(default=8, metadata={"min": 2, "max": 200, "step": 1, "unit": "states"})
    """Sliding-window length N: states older than the newest N are marginalised (their information stays as a
    linear prior). The newest estimate did not change (< 0.01 mm) between 8, 15 and 30 on the simulated landing,
    while each iSAM2 update costs more with N; 100 states, or re-optimising at every update with 5 iterations and
    relinearisation checked every update, left seeds 0-3 within 0.001 mm (replayed): the newest state of a
    fixed-lag smoother is the filter's estimate (marginalisation keeps the old states' information), so the window
    helps only the states that later registrations revisit, states.

    Session 29: re-using a frame's registration from a better start, which only a graph can do for a past state (swap
    state k-L's registration factor, at update k, for that frame registered again from the smoothed x_(k-L|k)), bounded
    on recorded inputs with session 20's echo model (a registration moves ``S`` times its start's move,
    :mod:`evpose.tracker.event_registration`; every registration also moved by ``S`` times its own prediction's change,
    so the loop's feedback is in; ``/tmp/s29/fuse29/causal.py``, 346x260 seeds 0-7, 5.297 mm as replayed): L = 7 (this
    window) 5.295, L = 30 (a 32-state window) 5.258 mm, for a second registration per update; on seed 0, L = 1 / 7
    6.514 -> 6.697 / 6.667 mm (worse: the smoothed start carries the estimate's own slow error, which the swapped
    registration then echoes as news). The smoothed states are only a little better than the online ones (seed 0, lag 1
    / 3 / 7: 6.30 -> 6.24 / 6.12 / 5.98 mm), while the same swap from the truth (an oracle) gives 3.60 / 4.57 mm at L =
    7 / 30: what a re-registration could reach needs a start better than any estimate the IMU and these
    registrations give. Not built."""
    reoptimize_every: int = field(default=5, metadata={"min": 1, "max": 100, "step": 1, "unit": "updates"})
    """Joint optimisation of the window every K updates."""
    reoptimize_iterations: int = field(default=2, metadata={"min": 1, "max": 20, "step": 1, "unit": "iterations"})
    """Extra relinearising iSAM2 iterations run at each joint optimisation."""
    relinearize_threshold: float = field(default=1.0e-3, metadata={"min": 1e-6, "max": 1.0, "step": 1e-4, "unit": "tangent"})
    """iSAM2 relinearisation threshold on the tangent-space delta of any variable. Session 13, closed loop, 346x260
    seeds 0-3 / 4-7 / 8-11: 1e-4 with ``relinearize_skip`` 1 and ``reoptimize_every`` 1 (the graph relinearising as
    much as it can, its one mechanism the EKF lacks) 6.42 / 5.97 / 6.07 mm, ARE 0.0677 / 0.0683 / 0.0639 deg against
    6.38 / 5.91 / 6.15, 0.0655 / 0.0676 / 0.0637: not kept."""
    relinearize_skip: int = field(default=10, metadata={"min": 1, "max": 100, "step": 1, "unit": "updates"})
    """iSAM2 checks which variables to relinearise only every this many updates (gtsam ``relinearizeSkip``); the
    window re-optimisation relinearises anyway. 10 instead of 1 cut the update's CPU time by ~20 % with the same
    estimates to 0.01 mm on the simulated landing, updates.

    Session 29, on the same recorded inputs (each graph run's registrations replayed, ``/tmp/s29/fuse29/same.py``,
    ``trig.py``; see :func:`evpose.bench.fusion_regimes.same_inputs_gap`), mean ATE mm default -> 1 (EKF): 2 s landings
    346x260 seeds 0-7 5.297 -> 5.293 (5.305), 8-11 4.766 -> 4.761 (4.762), 240x180 0-7 6.930 -> 6.909 (6.938); 3 s
    landings (346x260 seeds 0-3) 12.275 -> 12.032 (12.285), every seed lower, the gain in the turn and after it (seed
    0: 12.51 -> 11.61 mm RMS in the turn, 11.06 -> 10.47 after, 7.53 -> 7.37 before), where weak registrations move
    the states most: the one setting found that gives the graph an edge over the EKF of more than 0.03 mm on the same
    inputs. With ``relinearize_threshold`` 1e-4 too 5.278 / 4.756 / 6.924 / 12.177 mm, 0.3 s / 0.5 s outages
    (``regimes``, seeds 0-3) 8.822 -> 8.767 mm (EKF 8.871) at 0.5 s; ``reoptimize_iterations`` 5 or ``reoptimize_every``
    1 add nothing. Relinearising at every update only within 8 / 40 / 200 updates of a degraded one: 12.252 / 12.252
    / 12.204 mm. Cost (fusion update CPU on seed 0's inputs, load ~3.9): median 0.56 -> 0.80 ms, p99 1.70 -> 2.12 ms
    at 346x260 (1e-4 too: 1.07 / 2.79 ms), against the 3 ms per-update target (session 19: 2.48 ms wall median).
    In closed loop the front end's response hides it (a neutral nudge moves a seed by ~0.2 mm, see
    :mod:`evpose.bench.fusion_regimes`): 3 s landings 12.147 -> 12.144 mm (per seed 9.848 / 14.665 / 12.716 / 11.360
    -> 10.243 / 14.264 / 12.636 / 11.433; EKF 11.996), 2 s 346x260 seeds 0-7 5.287 -> 5.322 mm (+0.035 +- 0.020, 2
    of 8 lower; EKF 5.365), ARE 0.0591 -> 0.0594 deg. Not changed: it would take the latency budget's margin for a
    gain no closed-loop set of this size shows."""
    relinearize_correction_velocity: float = field(default=0.05, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "m/s"})
    """When an update moves the newest state's velocity by more than this from its IMU prediction, the window is
    relinearised at once (forced, whatever ``relinearize_skip``) and re-optimised; a re-acquisition's joint
    optimisation is forced likewise, m/s (0 = never: the window then relinearises only every ``relinearize_skip``
    iSAM2 calls, about once per state before it is marginalised).

    New states enter at their IMU prediction. In steady tracking an update corrects that by mm/s and the trigger
    does not fire: from ground truth the 2 s landings (seeds 0-7; 346x260 5.296 mm / 0.0589 deg, 240x180 7.270 mm /
    0.0796 deg) and the demos ``landing`` / ``landing_fast`` (9.953 / 18.560 mm) are bit-identical, the 3 s landings
    (seeds 0-7, 346x260, 12.77 mm) differ on one seed by 0.004 mm (a re-acquisition after the turn). A start without
    the initial velocity (``evpose track --init``) corrects it by m/s in its first updates, and the front end follows
    the fused motion, so that start is a knife edge for either backend. Bench ``fusion.regimes`` ``cold`` (no
    velocity, pose 3 cm / 1 deg off), seeds 0-7, runs that lost the track (ATE > 100 mm), the graph without / with
    the trigger / the EKF: 346x260 4 (seeds 0, 2, 3, 5) / 2 (2, 5) / 3 (3, 5, 6); with
    ``PolarityFilterConfig.unknown_velocity_hold_updates`` 40 but ``T_align`` off only 3 / 1 / 1, with that hold as
    it is 1 / 1 / 1 (seed 5; the seven kept 15.74 / 15.43 / 15.38 mm); 240x180 without the hold 1 / 2 / 0, with it
    none (22.95 / 22.99 / 22.84 mm). Weak evidence, a real mechanism: on 346x260 seed 0 without the hold (lost
    without the trigger, 3162 mm; the EKF 16.72) forced relinearisation at every joint optimisation only gave 2564 mm,
    relinearising at every update (``relinearize_skip`` 1, ``reoptimize_every`` 1, 5 iterations) 16.76, this trigger
    at 0.05 / 0.2 m/s 16.77 / 17.07 mm; no robust loss changed nothing (the kernel never engages). Replayed open
    loop on the EKF's recorded inputs the graph gives the EKF's velocities to 0.07 m/s with or without it. Outages
    from ground truth (0.1 / 0.3 / 0.5 s at 0.8 s, 346x260 seeds 0-7): 5.386 / 5.945 / 7.543 mm without, 5.388 /
    5.956 / 7.543 with it (the EKF 5.408 / 5.947 / 7.498)."""
    init_sigma_rot: float = field(default=0.01, metadata={"min": 1e-6, "max": 1.0, "step": 1e-4, "unit": "rad"})
    """Prior sigma on the initial orientation, rad. Started from ground truth, the fusion's first updates take a
    registration's image-shift error partly as a tilt (seed-mean error about camera x at the first update -34 mdeg);
    1e-4 (an exact start) gave seeds 0-3 (session 8, buffer-zone trail 0) 8.35 / 10.55 mm against 9.15 / 9.51 at
    346x260 / 240x180 (the shift then goes into the position): not kept. Session 9 (buffer-zone trail 0.1, 7.78 / 9.40
    mm): 0.002 / 5e-4 gave 7.72 / 9.81, 7.63 / 10.15 mm, the EKF better than the graph at 346x260 either way."""
    init_sigma_trans: float = field(default=0.01, metadata={"min": 1e-6, "max": 10.0, "step": 1e-4, "unit": "m"})
    """Prior sigma on the initial position, m."""
    init_sigma_velocity: float = field(default=0.5, metadata={"min": 1e-4, "max": 20.0, "step": 0.01, "unit": "m/s"})
    """Prior sigma on a given initial velocity, m/s. (The tracker gives one only when starting from ground truth.)
    0.01 gave seeds 0-3 8.5 / 9.2 mm against 9.1 / 9.6 but the demos 20.1 / 18.0 / 23.8 mm against 16.0 / 23.2 /
    21.0: not kept. Session 18, 240x180 seeds 0-7 (7.325 mm): 0.02 gave 7.94 mm; with ``init_sigma_rot`` and
    ``init_sigma_trans`` 1e-3 7.60 mm; 0.005 with both 1e-4 (the start known exactly, as it is) 8.38 mm."""
    unknown_velocity_sigma: float = field(default=10.0, metadata={"min": 0.1, "max": 100.0, "step": 0.1, "unit": "m/s"})
    """Prior sigma on the initial velocity when none is given (it starts at zero), m/s."""
    init_sigma_acc_bias: float = field(default=0.1, metadata={"min": 1e-5, "max": 2.0, "step": 1e-3, "unit": "m/s^2"})
    """Prior sigma on the initial accelerometer bias, m/s^2. (0.05, the simulator's: seeds 0-3 8.71 / 10.88 mm against
    7.78 / 9.40, session 9.) Session 14, with the event registration, 240x180 seeds 0-3 (7.25 mm, ARE 0.076 deg): 0.05
    / 0.2 / 0.5 / 1.0 gave 8.46 / 6.84 / 6.51 / 6.38 mm (ARE 0.086 / 0.077 / 0.081 / 0.083); 0.5 at 240x180 seeds 4-7
    8.03 mm (8.49, ARE 0.097 against 0.088), 346x260 seeds 0-3 5.97 mm (6.38), but the demo ``landing`` 10.99 / 10.91
    mm at 0.5 / 1.0 against 9.71 (see ``init_sigma_acc_bias_vertical``). What the 2 s run's error rests on: with the
    simulator's true biases at the start, held tight (sigma 1e-4 / 1e-5), 240x180 seeds 0-3 give 3.40 mm; the true
    gyroscope bias alone (and the vertical accelerometer prior 0.5) 5.06 mm; the true accelerometer bias alone
    6.05 mm (5.64 with the gyroscope's started at its true value, sigma 0.01) (``/tmp/s14/fullacc/orbias.py``). The
    registrations' own slow errors, which the biases absorb, are shared by the field's and the events' poses (about the
    optical axis both drift from ~+0.01 to ~-0.12 deg over seeds 0 and 2; with the simulator's true edges as the map
    the combined pose still ends at -0.12 / -0.06 deg), so no prior separates them."""
    init_sigma_acc_bias_vertical: float = field(default=0.0, metadata={"min": 0.0, "max": 5.0, "step": 1e-3, "unit": "m/s^2"})
    """Prior sigma on the initial accelerometer bias along gravity (the IMU frame's direction of world z at the
    start), m/s^2 (0 = ``init_sigma_acc_bias``, as across it).

    A horizontal bias is confounded with tilt (gravity leaking through a tilt error), a vertical one only with the
    height the registrations hold weakly (the image's scale); with ``init_sigma_acc_bias`` the graph keeps it near
    zero for the first ~0.8 s of the 2 s landing (seed 0 at 240x180: the estimate's error along z 0.080 -> 0.052
    m/s^2 by 0.8-1.2 s, the height error up to 14 mm). Session 14, ``full``, 2 s landing from ground truth, mean ATE
    mm / ARE deg of seeds 0-3, 4-7, 8-11 (``/tmp/s14/fullacc/run.py``), 0 -> 0.5: 346x260 6.38 / 5.91 / 6.15 -> 6.08
    / 5.54 / 5.76 mm, ARE 0.0655 / 0.0676 / 0.0637 -> 0.0649 / 0.0651 / 0.0631 deg; 240x180 7.25 / 8.49 / 8.43 ->
    6.74 / 7.80 / 7.17 mm, ARE 0.0760 / 0.0875 / 0.0887 -> 0.0788 / 0.0888 / 0.0865 deg; the EKF with it 6.11 / 5.68
    / 5.90 and 6.74 / 7.96 / 7.35 mm (24-run mean: graph 6.513 mm / 0.0745 deg, EKF 6.621 / 0.0754). But the longer,
    higher flights (``evpose track ... --map maps/landing_map.ply``, ``evpose eval --align none``, ATE RMSE) got worse:
    demo ``landing`` 9.71 -> 9.88, ``landing_fast`` 18.20 -> 18.44, ``landing_dynamic`` 12.27 -> 13.52 mm and the same
    3 s flight without moving objects 12.47 -> 15.06 mm: better in their first second (height error RMS 3.1 -> 1.3
    mm), then the bias follows the registrations' height errors (second 1-2: 4.4 -> 12.4 mm); 0.3 / 0.2: 10.03 /
    9.86, 16.74 / 17.99, 13.36 / 13.35 mm (3 s flight 14.55 mm at 0.3); with ``accel_bias_random_walk`` 3e-4 the
    3 s flight 15.23 mm (240x180 seeds 0-3 6.61); three more 3 s landings (seeds 1 / 2 / 3, their own built maps, see
    ``registration.fused_lag_floor_px``) 18.38 / 16.33 / 15.28 -> 21.12 / 17.60 / 14.97 mm. 240x180 seeds 0-3: 0.3 /
    1.0 6.70 / 6.88 mm; 0.5 with 0.05 across 7.68 mm. Not kept (off). On those 3 s landings
    ``registration_covariance_scale`` 10, ``accel_bias_random_walk`` 3e-4 and ``constant_velocity_sigma`` 0.5 gave
    20.68 / 17.99 / 16.96, 17.95 / 16.22 / 15.36 and 19.36 / 16.47 / 16.23 mm."""
    init_sigma_gyro_bias: float = field(default=0.01, metadata={"min": 1e-6, "max": 0.5, "step": 1e-4, "unit": "rad/s"})
    """Prior sigma on the initial gyroscope bias, rad/s. (The simulator's IMU draws 0.002 per axis.) 0.002 gave seeds
    0-3 (closed loop, session 8, buffer-zone trail 0) 8.74 / 11.46 mm against 9.15 / 9.51 (ARE up to 0.18 deg),
    0.003 / 0.001 replayed 8.21 / 8.16 at 346x260: the replay (open loop) does not see that a rotation held to a
    biased gyro moves the next registrations' start, not kept. Session 9 (7.78 / 9.40 mm, ARE 0.077 / 0.098 deg):
    0.003 / 0.005 gave 7.55 / 10.02, 7.32 / 9.60 mm, ARE 0.090 / 0.117, 0.080 / 0.102 deg. The graph's gyro-bias
    error stays 1-2 mrad/s over the 2 s (the true bias: 0.002 per axis), the accelerometer's is learnt only after
    ~1 s: a 2 s run does not hold the information. Session 14, with the event registration, 240x180 seeds 0-3
    (7.25 mm): 0.003 / 0.005 / 0.02 gave 8.02 / 7.53 / 8.22 mm (ARE 0.099 / 0.081 / 0.092 deg against 0.076); with the
    vertical accelerometer prior 0.5 (6.74 mm), the gyroscope bias about gravity at 0.003 / 0.03 (0.01 across) 6.91 /
    6.75 mm, 0.005 across (0.01 about gravity) 7.19 mm.

    Session 18 (``/tmp/s18/seedvar7/``; ``full``, 2 s landing, 240x180 seeds 0-7 7.325 mm, 346x260 5.30 mm): the
    spread between seeds is the simulator's bias draws. At 240x180 ATE^2 = 11.1 mm^2 + 1.60e4 |ba_z|^2 + 3.2e3
    |ba_xy|^2 + 2.33e6 |bg_xy|^2 (camera frame, m/s^2 and rad/s) explains 83 % of its variance over seeds 0-11; the
    height error follows |ba_z| (correlation 0.81) and the sideways error |bg_xy| (0.85), and builds up from 0.5 s to
    1.4 s, not at the start. The simulator's true biases at the start, held tight (``orbias.py``): gyroscope
    alone 5.27 mm, accelerometer alone 6.45, both 3.24 mm at 240x180 (seeds 4 / 0 / 11 at 11.7 / 10.6 / 12.3 mm
    without); at 346x260 gyroscope alone 3.90, both 3.24 mm. The information is not in the run's registrations: a
    batch smoother over the whole run's recorded fusion inputs (one window of every state, ``batchbias.py``) ends
    at the online filter's biases to within 0.1 mrad/s (seed 0: 1.4 / 0.4 / 1.7 mrad/s off the truth, seed 2: 0.9 /
    0.3 / 1.6), because in tilt against sideways shift and in height the registrations keep the prediction they
    start from (``registration.prior_rotation_deg``): the field and the events started and held at the truth instead
    (an oracle) give 4.32 mm at 240x180 seeds 0-7, only the tilt/sideways components 5.67 mm.

    Session 20 (``/tmp/s20/res7/diag.py``, ``an.py``; seeds 0-7, every update): world-frame position error RMS x / y /
    z 2.79 / 5.51 / 4.65 mm at 240x180 against 2.65 / 3.84 / 2.78 at 346x260, the excess in y and height, built from
    0.5 s (0-0.5 s 2.3 / 2.6 / 1.3 mm, then 2.7 / 5.8 / 5.4 mm); in the camera frame rotation about x 62 mdeg and
    translation along y 5.5 mm (the tilt/sideways pair). The accelerometer bias error falls from 0.05 to ~0.01 m/s^2
    per axis by 1-1.5 s at both sizes; the gyroscope bias error from ~2 to 0.9 / 0.3 / 1.1 mrad/s (IMU axes) at
    240x180 and 0.6 / 0.5 / 0.6 at 346x260 by the end: the gyroscope bias is what 240x180 leaves unlearnt.

    Session 41 (fl41, ``/tmp/s41/fl41``: ``run.sh``, ``cmp.py``; ``full`` from ground truth, the CLI path, paired
    against main's defaults): on other flights of the landing (``evpose simulate --flight N --seed 1000+N``, 240x180
    2 s, each on its own built map) the registrations sit off the truth along the shift / tilt ridge for most of the
    flight (flight 2, every registration started from the true pose, ``oracle.py``: camera x -9.5 mm / tilt about y
    +145 mdeg over 0.25-1.25 s, against +6.8 / -55 over 0.25-0.5 s and ~0 after on the nominal flight; the map's
    points snapped onto the true edges change nothing, the top rims of the 1 m box the flight leaves behind carry
    half of it), and the fused tilt drifts past them (+413 against +290 mdeg at 1.75-2 s): the graph learns that
    ridge as a gyroscope bias. A tighter prior holds it: 0.003 flights 1-10 14.391 -> 11.927 mm (-2.46 +- 0.72, 7 of
    10 better; ARE 0.191 -> 0.151 deg), but the nominal flight's seeds 0-11 4.630 -> 5.919 (+1.29 +- 0.72, 4 of 12;
    seed 4 5.12 -> 13.42 mm); 0.005 flights 1-12 14.187 -> 12.412 (-1.78 +- 0.41, 11 of 12; ARE 0.189 -> 0.165),
    held-out flights 13-16 12.612 -> 12.522 (-0.09 +- 0.55, 2 of 4), nominal seeds 0-11 4.630 -> 5.130 (+0.50 +-
    0.36, 4 of 12; seed 4 5.12 -> 9.06; ARE 0.057 -> 0.063). The lead, 0.005 on the whole sets
    (``/tmp/s41/lead/trk/runc.sh gb5 CFG CASE...``, pairs against ``out/main``): 240x180 held-out flights 13-24 14.906 ->
    13.811 mm (-1.10 +- 0.43, 9 of 12), 346x260 flights 1-12 and 15 12.956 -> 11.722 (-1.23 +- 0.53, 10 of 13), nominal
    240x180 seeds 0-23 4.770 -> 5.365 (+0.60 +- 0.22, 6 of 24). It trades the nominal flight for the others: not
    changed in session 41; the first candidate once tuning moves to the flights.

    Session 42 (tune42, ``/tmp/s42/tune42``; tuning set 240x180 flights 1-12, held out flights 13-24 and 346x260
    flights; every figure in docs/measurements.md): 0.007 / 0.006 / 0.005 move the flights by -0.82 / -1.27 / -1.78 mm
    and the nominal flight by +0.18 / +0.32 / +0.60 mm, the demo ``landing`` 6.554 -> 7.904 mm at 0.007. The nominal
    flight's loose prior learns a real bias (its loss follows the simulator's true |bg_xy|, correlation +0.89), while
    on the flights the graph learns the registrations' ridge error; the two have the same size and are learnt in the
    same first second, so no prior width separates them. With the lone lead on (the lead, ``/tmp/s42/lead/trk``:
    ``runtc.sh``, ``sum.py``, against ``contrast.lone_lead_px`` -0.1 alone): 0.007 240x180 flights 1-24 12.962 -> 12.404
    (-0.56 +- 0.16, 18 of 24), 346x260 flights 11.198 -> 10.637 (-0.56 +- 0.26, 11 of 13), nominal seeds 0-23 4.922 ->
    5.151 (+0.23 +- 0.09, 6 of 24). Not changed; a real IMU's prior belongs to its datasheet."""
    gyro_bias_hold_s: float = field(default=0.0, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "s"})
    """For this long after each start of the fusion (``initialize``) the gyroscope bias is held at its initial value
    (prior sigma ``gyro_bias_hold_sigma`` instead of ``init_sigma_gyro_bias``), then released: the first state at or
    after it gets the initial prior's uncertainty (``init_sigma_gyro_bias``) as a one-step random-walk jump, so the
    bias is learnt from the registrations after the hold only, s (0 = off: the prior applies at the start).

    Why: at 240x180 the registrations swing along the shift-along-x / tilt-about-y ridge in the first ~0.5 s of a
    track (session 32, docs/measurements.md), which the graph learns as a gyroscope bias about y (its error positive
    on 12 of 12 seeds at 0.25 s) and then holds the fused state on the ridge; a tighter prior for the whole run
    (``init_sigma_gyro_bias`` 0.003 / 0.005) shrank the offset but cost ATE. Measured (session 33, ``full`` from
    ground truth, the CLI path on the cached 240x180 2 s landings, ``/tmp/s33/gyro33/run.sh``, ``cmp.py``; defaults
    5.568 mm over seeds 0-23): 0.25 s seeds 0-13 5.281 -> 6.624 mm (+1.34 +- 0.28, 0 of 14 better, ARE 0.065 ->
    0.083 deg), 0.5 s seeds 0-12 5.371 -> 7.551 (+2.18 +- 0.52, 0 of 13): far worse, so off. The simulator's gyroscope
    bias (0.002 rad/s per axis) is what the first registrations teach the graph, start-up swing or not: held at zero
    the rotation drifts by bias x time and the bias is learnt only after the release."""
    gyro_bias_hold_sigma: float = field(default=1.0e-5, metadata={"min": 1e-8, "max": 0.5, "step": 1e-5, "unit": "rad/s"})
    """Prior sigma on the initial gyroscope bias while ``gyro_bias_hold_s`` holds it, rad/s (tiny: held; the bias
    random walk over the hold is ~1e-5 rad/s as well)."""
    registration_startup_s: float = field(default=0.5, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "s"})
    """For this long after each start of the fusion (``initialize``) the registration covariance is widened along its
    two least-constrained directions (the shift / tilt ridges, see ``factor_graph.STARTUP_RIDGE_DIRECTIONS``) by
    ``registration_startup_inflation``, s (0 = off). Why: the registrations swing along the shift-along-x / tilt-about-y
    ridge in a track's first ~0.5 s (session 32), which the graph learns as a gyroscope bias and then holds the fused
    state on that ridge. Only then is the ridge over-confident: session 32's per-update logs (``pred.py``; 240x180
    seeds 0-11, registration error in (h roty, x), h the height, against the scaled covariance's 2x2 block, whose
    weak eigen-direction is the ridge (x - h roty) / sqrt 2 with 12.5x the strong one's sigma) give a mean squared
    normalised error along the ridge 0.79 / 0.34 / 0.14 times that along the strong direction over 0-0.5 / 0.5-1 /
    1-2 s (346x260 seeds 0-3: 2.82 / 1.05 / 0.12; ``/tmp/s33/gyro33/nees.py``), so a floor on the ridge for the
    whole run is not what the errors ask for.

    Session 33, ``full`` from ground truth, the CLI path (``evpose track r.h5 --map m.ply --init gt --mode full``,
    ``evpose eval --align none``) on the cached landings (``/tmp/s33/gyro33/run.sh``, ``cmp.py``, ``demos.py``),
    paired against 0: 240x180 2 s seeds 0-23 (5.568 mm) at (s, inflation) (0.3, 10) 5.501 (-0.067 +- 0.040, 13 of 24
    better), (0.5, 10) 5.482 (-0.086 +- 0.081, 14 of 24; ARE 0.0667 -> 0.0653 deg), (0.5, 100) 5.484 (-0.084 +-
    0.091), (1.0, 10) 5.671 (+0.103 +- 0.121, 7 of 24); (0.5, 10) on held-out seeds 24-47 6.091 -> 5.925 (-0.165 +-
    0.046, 19 of 24; ARE 0.0707 -> 0.0684), 346x260 2 s seeds 0-23 4.529 -> 4.279 (-0.250 +- 0.059, 19 of 24; ARE
    0.0538 -> 0.0504), 240x180 3 s seeds 0-7 15.889 -> 14.702 (-1.19 +- 0.28, 8 of 8; ARE 0.1055 -> 0.0999); the demos
    (``evpose track demo_data/X.h5 --map maps/landing_map.ply``) ``landing`` 6.615 -> 6.899, ``landing_fast`` 9.357 ->
    9.132, ``landing_dynamic`` 5.697 -> 6.312 mm, and the same with the graph nudged neutrally (``constant_velocity_sigma``
    2.2 / 1.8: 6.677 / 6.658 -> 6.953 / 7.029, 9.390 / 9.444 -> 9.156 / 9.246, 5.804 / 5.778 -> 6.303 / 6.328 mm), so
    ``landing`` and ``landing_dynamic`` are worse beyond their chaos; ``landing_dynamic``'s extra error comes after
    1.5 s, not in the start (``errtime.py``). Other shapes on the demos: (0.3, 10) 6.211 / 9.369 / 6.309 mm, (0.5, 3)
    6.693 / 9.248 / 5.946, (0.5, 10) with ``gyro_bias_random_walk`` 1e-3 7.248 / 9.288 / 6.113. ``landing_dynamic`` is
    simulator seed 0 of ``evpose simulate --scenario landing_dynamic --seconds 3 --resolution 346x260``: simulated again
    with seeds 0-9, each on its own built map (``/tmp/s33/gyro33/dyn.sh``, ``dyncmp.py``), 6.737 -> 6.181 mm (-0.56 +-
    0.16, 9 of 10 better; seed 0 5.782 -> 6.152, the one worse, as its demo), but ARE 0.0626 -> 0.0676 deg (7 of 10
    worse). The lead then measured the demos' own recipes on other seeds, each on its own built map, and the pair on top
    of ``event_registration.coarse_on_lead_px`` (``/tmp/s33/lead/l4.sh``, ``lf.sh``, ``sum4.py``, ``run.sh``, ``cmp.py``):
    ``landing`` 4 s 346x260 seeds 1-8 7.100 -> 6.515 mm (-0.585 +- 0.112, 7 of 8 better; ARE 0.0614 -> 0.0569 deg, 7
    of 8), ``landing_fast`` 2.5 s seeds 1-6 7.327 -> 7.055 (-0.271 +- 0.066, 5 of 6; ARE 6 of 6 better); with the
    coarse ON leads, 240x180 2 s seeds 0-23 5.398 -> 5.255 (-0.143 +- 0.074, 14 of 24), held-out 24-47 5.815 -> 5.652
    (-0.163 +- 0.058, 18 of 24), 3 s seeds 0-7 14.495 -> 13.512 (-0.98 +- 0.24, 7 of 8). So on since session 33: every
    simulated set gains; the bundled ``landing`` and ``landing_dynamic`` demos are the seed-0 draws that lose (6.615
    -> 6.899, 5.697 -> 6.312 mm). What it does (``pred.py``, ``table.py``, 240x180 seeds 0-5, (0.5,
    10)): the fused state's mean ridge offset +2.62 -> +1.84 mm, the prediction's lead along the flight +2.54 -> +1.80
    mm, the gyroscope bias's error about y at 0.5 s +1.54 -> +1.08 mrad/s (seed mean)."""
    registration_startup_inflation: float = field(default=10.0, metadata={"min": 1.0, "max": 1e6, "step": 1.0, "unit": "ratio"})
    """Factor on the variance along those directions during ``registration_startup_s``, ratio."""
    registration_startup_directions: int = field(default=2, metadata={"min": 1, "max": 6, "step": 1, "unit": "directions"})
    """How many of the registration covariance's least-constrained directions (the largest eigenvalues of its
    correlation matrix) ``registration_startup_inflation`` and ``registration_ridge_scale`` widen, directions (2: the
    two shift / tilt ridges, ``startup.STARTUP_RIDGE_DIRECTIONS``). Session 34, 240x180 2 s seeds 0-23 (``/tmp/s34/bias34/``,
    ``replay.py``: the recorded fusion inputs of the defaults replayed open loop, 5.205 mm there, where
    ``registration_startup_s`` 0 gives +0.104 +- 0.044 mm, the closed loop's sign and size): 1 / 3 / 4 / 6 directions
    5.237 / 5.167 / 5.223 / 5.223 mm; closed loop (``run.sh``, ``cmp.py``) 3 directions 5.255 -> 5.245 mm (-0.009 +-
    0.080, 11 of 24 better; ARE 0.0603 -> 0.0615 deg). Replayed the same way, ``registration_startup_s`` 0.3 / 0.75 s
    +0.031 / +0.111 mm, inflation 30 -0.000, and the factor tapered geometrically to 1 over 0.25 / 0.5 / 1.0 s after
    the 0.5 s +0.083 / +0.103 / +0.243 mm (after 0.3 s, over 0.5 / 1.0 s: +0.048 / +0.134): a longer de-weighting of
    the ridge is worse. Not changed.

    Session 42 (tune42, other flights, see ``init_sigma_gyro_bias``), 1.0 s (inflation 10): 240x180 flights 1-12
    14.187 -> 14.123 mm (-0.064 +- 0.627, 5 of 12 better; flights 3 / 9 -3.8 / -3.3 mm, 10 / 11 +2.6 / +3.0), the
    nominal flight's seeds 14-23 5.098 -> 5.475 (+0.377 +- 0.126, 1 of 10): the flights' ridge error lasts from
    0.25 s to the end, and widening it for longer does not keep it out of the gyroscope bias."""
    registration_ridge_scale: float = field(default=1.0, metadata={"min": 1e-3, "max": 1e6, "step": 0.05, "unit": "ratio"})
    """Factor on the registration covariance's variance along the same two ridge directions after
    ``registration_startup_s`` (the whole run when that is 0), ratio (1 = off). After the start the ridge carries less
    error than its covariance claims relative to the best-observed direction (``registration_startup_s``), so a
    smaller scale would let the fused state return to the registrations faster; session 33, 240x180 2 s seeds 0-23,
    0.5 alone: 5.568 -> 5.654 mm (+0.086 +- 0.083, 11 of 24 better): off. Session 41 (fl41, other flights of the
    landing, see ``init_sigma_gyro_bias``): 3.0 flights 2 / 3 / 4 / 5 19.83 / 18.72 / 9.65 / 16.83 -> 17.02 / 17.47 /
    8.52 / 16.12 mm (-1.48 +- 0.46, 4 of 4 better), the nominal flight's seeds 0 / 1 / 2 6.42 / 4.42 / 5.55 -> 6.97 /
    4.87 / 5.62 (+0.36 +- 0.15, 0 of 3): a trade as well, off."""
    registration_offset_tau_s: float = field(default=0.0, metadata={"min": 0.0, "max": 100.0, "step": 0.05, "unit": "s"})
    """Correlation time of a registration offset along the shift / tilt ridges that the factor graph estimates with the
    poses (a first-order Gauss-Markov state per registered state, :mod:`evpose.fusion.registration_offset`), s (0 =
    off: the registrations' errors white; the EKF always takes them as white).

    Why: the registrations' ridge error is slow (session 33: +6.6 mm for the flight's first ~0.6 s), and a white model
    hands it to the pose and the gyroscope bias. What knowing it would be worth (session 34, ``/tmp/s34/bias34/oracle.py``:
    the defaults' recorded fusion inputs, 240x180 2 s seeds 0-23, replayed open loop with the registrations' ridge
    component (the two ridge directions of their own covariance) taken out, 5.205 mm as recorded): all of it 4.210 mm
    (-0.995 +- 0.124, 24 of 24 better), its slow part (0.3 s centred mean) 4.196 (-1.010 +- 0.137), its slow part
    before 0.6 s only 5.039 (-0.167 +- 0.059); the slow part of the whole error (6 axes) 2.740 (-2.465 +- 0.214). So
    the start-up swing is a small part: the ridge's slow error after it is worth ~0.8 mm, and depth and the other
    slow errors more.

    Measured (session 34, ``full`` from ground truth, closed loop: ``run.sh`` + ``rec.py``, the CLI's ``track`` in
    process with identical output, ``cmp.py``; 240x180 2 s landing, defaults 5.255 mm / ARE 0.0603 deg on seeds
    0-23): (tau, ``registration_offset_ratio``) (0.3, 3) 5.190 mm (-0.065 +- 0.051, 16 of 24 better; ARE 0.0578);
    held-out seeds 24-47 5.652 -> 5.627 (-0.025 +- 0.093, 16 of 24; ARE 0.0629 -> 0.0605); the 3 s landing seeds 0-7
    13.512 -> 14.025 (+0.512 +- 0.431, 2 of 8; ARE 0.1113 -> 0.1000); 346x260 2 s seeds 0-23 4.279 -> 4.497 (+0.218
    +- 0.052, 4 of 24; ARE 0.0504 -> 0.0533); the demos (``evpose track demo_data/X.h5 --map maps/landing_map.ply``,
    ``evpose eval --align none``; ``demo.sh``) ``landing`` 6.899 -> 7.974, ``landing_fast`` 9.132 -> 9.285,
    ``landing_dynamic`` 6.312 -> 6.146 mm. Worse at 346x260, on the 3 s landing and the demo ``landing``: off.
    Open loop (``replay.py``, 5.205 mm there) seeds 0-23: (0.3, 1) -0.026, (1, 1) -0.006, (0.3, 3) -0.047, (1, 3)
    -0.036; (0.3, 10) +0.051, (0.15, 10) +0.065, (0.6, 10) +0.045, (0.3, 30) +0.30 mm: a larger slow share is worse.
    An earlier form that added the offset's variance to the registration's instead of sharing it (the ridge weighed
    less in all) was worse: closed loop (0.5, 1) 5.430 mm (+0.175 +- 0.094, 8 of 24 better; ARE 0.0634), open loop
    +0.04 to +0.13 mm for tau 0.3-3 s and ratios 0.03-0.3. Why the gain is small: the fused pose itself is free to
    follow a slow error (its start prior 1 cm / 10 mrad, velocity 0.5 m/s, biases unknown; a tilt error is an
    accelerometer bias to the IMU), so with the offset a synthetic flight's pose moves onto a constant ridge error more slowly only for
    its first ~0.1 s (``tests/fusion/test_ridge_offset_s34.py``), and on the landings the offset only shares the
    ridge error by its prior's statistics. Cost: 0.63 ->
    1.55 ms CPU per fusion update at (0.3, 3) (``cost.py``, seed 0's inputs replayed, best of 5): an extra Pose3 and
    three factors per state in the window. Session 42 (tune42, other flights, where the ridge error is slow and large:
    see ``init_sigma_gyro_bias``), (0.3, 3) on 240x180 flights 1-12 14.187 -> 14.349 mm (+0.162 +- 0.241, 6 of 12
    better; ARE 0.1885 -> 0.1909 deg): sharing the ridge variance with a slow offset does not keep that error out of
    the gyroscope bias either."""
    registration_offset_ratio: float = field(default=3.0, metadata={"min": 1e-3, "max": 1e4, "step": 0.1, "unit": "ratio"})
    """With ``registration_offset_tau_s``: the offset's stationary variance along the two ridge directions over the
    registration factor's own (white) variance there. The two share the (scaled, start-up widened) registration
    covariance's ridge variance, so each registration's total stays as without the offset: the offset takes
    ``ratio / (1 + ratio)`` of it, ratio."""
    newest_state_last: bool = True
    """The fixed-lag smoother eliminates the newest two states last, so the newest sits in the Bayes tree's root
    (False: gtsam's ``IncrementalFixedLagSmoother`` ordering exactly, one group for every kept key, which leaves
    the newest state in a leaf below a chain that grows until the next relinearisation). Each update then
    re-eliminates only the root instead of that chain, and the newest state's marginal covariance needs no
    shortcuts through it. Estimates differ from gtsam's ordering by rounding (fused positions within 0.0002 mm
    on the simulated landing, replayed). Measured in session 9 (2 s landing 346x260 seed 0, its recorded fusion
    inputs replayed, CPU per update, alternated, load 4.2): update without covariance 0.43 -> 0.33 ms median,
    the covariance 0.111 -> 0.044 ms, whole update 0.49-0.52 -> 0.37 ms."""
    compute_covariance: bool = True
    """Report the marginal pose covariance with every update (costs a little latency: session 19, ``full`` at 346x260
    seed 0, in-process A/B against it on, same poses, 2 rounds at load ~3.6: CPU per update 0.08-0.10 ms less
    without it, which the fused estimate itself never reads)."""
    revision_readout_states: int = field(default=7, metadata={"min": 0, "max": 199, "step": 1, "unit": "states"})
    """Write each state's pose moved by ``revision_readout_gain`` times the mean revision the smoother has made to the
    L older states of its window since they were written (factor graph only; at most ``window_states`` - 1; 0 =
    off); tracking is unchanged. Session 36, against off: 240x180 5.255 -> 5.060 mm (held-out 5.652 -> 5.489), 346x260
    4.279 -> 4.169; every figure in :mod:`evpose.fusion.revision_readout`. Session 42 (tune42), off on the other
    flights (240x180 flights 1-12, where the fused tilt drifts past the registrations): 14.187 -> 14.514 mm (+0.327
    +- 0.109, 2 of 12 better): the read-out does not cause that drift, it helps there too."""
    revision_readout_gain: float = field(default=2.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "ratio"})
    """With ``revision_readout_states``: the factor on the mean revision (see that module), ratio."""
    revision_readout_depth_ratio: float = field(default=2.0, metadata={"min": 0.0, "max": 10.0, "step": 0.1, "unit": "ratio"})
    """With ``revision_readout_states``: the position revision's component along the camera's optical axis gets
    ``revision_readout_gain`` times this (1 = the same gain on every axis): depth is what the registrations observe
    least, and its revision the smallest part of its error. Not within ``registration_startup_s`` of the start (the
    registrations widened). Session 37 with ``revision_readout_position_smoothing`` 0.5, against both off
    (``/tmp/s37/ar37/run.sh``, ``cmp.py``): 240x180 5.060 -> 4.982 mm (held-out 5.489 -> 5.410), 346x260 4.169 ->
    4.161, 3 s 13.387 -> 13.392, ARE unchanged; every figure in :mod:`evpose.fusion.revision_readout`, ratio."""
    revision_readout_position_smoothing: float = field(default=0.5, metadata={"min": 0.01, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """With ``revision_readout_states``: the written position correction is this times the new one plus the rest
    times the previous state's (a causal exponential average; 1 = none): the corrections jitter from update to
    update, which the written trajectory's RTE shows. Session 37 with ``revision_readout_depth_ratio`` 2: RTE 0.518
    -> 0.395 mm at 240x180 (0.310 -> 0.263 at 346x260; 0.679 with the depth ratio alone, ungated), ATE +0.006 mm
    against the depth ratio alone (replayed); figures in :mod:`evpose.fusion.revision_readout`, ratio."""
    revision_readout_prior: bool = False
    """Also move the tracker's pose and the next prediction by the read-out's correction (a closed loop): +0.054 +-
    0.035 mm against the read-out alone (240x180 seeds 0-23, 8 of 24 better), so off."""

    def validate(self) -> None:
        from evpose.errors import ConfigError

        positive = ("accel_noise_density", "gyro_noise_density", "accel_bias_random_walk", "gyro_bias_random_walk", "gravity",
                    "registration_loss_scale", "registration_covariance_scale", "registration_default_sigma_rot", "registration_default_sigma_trans",
                    "constant_velocity_sigma", "unknown_velocity_sigma", "init_sigma_rot", "init_sigma_trans", "init_sigma_velocity",
                    "init_sigma_acc_bias", "init_sigma_gyro_bias", "relinearize_threshold", "registration_ar_covariance_scale",
                    "registration_ar_between_scale")
        for name in positive:
            if not getattr(self, name) > 0:
                raise ConfigError(f"fusion.{name} must be positive, got {getattr(self, name)}")
        if not self.relinearize_correction_velocity >= 0:
            raise ConfigError(f"fusion.relinearize_correction_velocity must be >= 0 (0 = off), got {self.relinearize_correction_velocity}")
        if not self.registration_ridge_scale > 0:
            raise ConfigError(f"fusion.registration_ridge_scale must be positive, got {self.registration_ridge_scale}")
        if not self.registration_offset_tau_s >= 0 or not self.registration_offset_ratio > 0:
            raise ConfigError(f"fusion.registration_offset_tau_s must be >= 0 and fusion.registration_offset_ratio positive, got {self.registration_offset_tau_s}, {self.registration_offset_ratio}")
        if self.registration_offset_tau_s > 0 and RegistrationErrorModel(self.registration_error_model) is not RegistrationErrorModel.WHITE:
            raise ConfigError("fusion.registration_offset_tau_s needs fusion.registration_error_model white (the offset models the errors' time structure itself)")
        if not 1 <= self.registration_startup_directions <= 6:
            raise ConfigError(f"fusion.registration_startup_directions must be 1-6, got {self.registration_startup_directions}")
        if not self.registration_startup_s >= 0 or not self.registration_startup_inflation >= 1:
            raise ConfigError(f"fusion.registration_startup_s must be >= 0 and fusion.registration_startup_inflation >= 1, got {self.registration_startup_s}, {self.registration_startup_inflation}")
        if not self.gyro_bias_hold_s >= 0 or not self.gyro_bias_hold_sigma > 0:
            raise ConfigError(f"fusion.gyro_bias_hold_s must be >= 0 and fusion.gyro_bias_hold_sigma positive, got {self.gyro_bias_hold_s}, {self.gyro_bias_hold_sigma}")
        if not self.init_sigma_acc_bias_vertical >= 0:
            raise ConfigError(f"fusion.init_sigma_acc_bias_vertical must be >= 0 (0 = off), got {self.init_sigma_acc_bias_vertical}")
        if not 0.0 <= self.registration_ar_rho < 1.0:
            raise ConfigError(f"fusion.registration_ar_rho must be in [0, 1), got {self.registration_ar_rho}")
        if self.window_states < 2:
            raise ConfigError(f"fusion.window_states must be >= 2, got {self.window_states}")
        if not 0 < self.revision_readout_position_smoothing <= 1:
            raise ConfigError(f"fusion.revision_readout_position_smoothing must be in (0, 1], got {self.revision_readout_position_smoothing}")
        if not self.revision_readout_states >= 0 or not self.revision_readout_gain >= 0 or not self.revision_readout_depth_ratio >= 0:
            raise ConfigError("fusion.revision_readout_states, fusion.revision_readout_gain and fusion.revision_readout_depth_ratio must be >= 0, "
                              f"got {self.revision_readout_states}, {self.revision_readout_gain}, {self.revision_readout_depth_ratio}")
        if self.reoptimize_every < 1 or self.reoptimize_iterations < 1 or self.relinearize_skip < 1:
            raise ConfigError("fusion.reoptimize_every, fusion.reoptimize_iterations and fusion.relinearize_skip must be >= 1")
