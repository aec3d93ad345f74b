"""Settings of the ``stpe`` mode's constant-velocity Kalman filter (:mod:`evpose.tracker.motion_filter`).

Its own module, like :mod:`evpose.tracker.registration_config`: the fields carry the measured history of each
setting, which outgrew the filter's code.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field


class VelocityFrame(str, enum.Enum):
    """The frame in which the filter holds the linear velocity constant between registrations."""

    WORLD = "world"
    """Constant body angular rate and constant world-frame velocity: a camera that turns while it flies straight
    (a drone yawing on its way down) keeps its velocity, so the model needs no acceleration to follow it."""
    BODY = "body"
    """Constant body-frame twist (a screw motion): turning also turns the velocity, so a camera that yaws at
    ``w`` while flying straight at ``v`` looks to the model like a sideways acceleration of ``w v``
    (1-1.5 m/s^2 on the simulated landing) that the filter follows with a lag."""


@dataclass
class MotionFilterConfig:
    """Constant-velocity Kalman filter settings (``stpe`` mode with ``motion_model: kalman``)."""

    angular_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "rad/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white angular acceleration driving the twist, rad/s^2/sqrt(Hz).

    On the simulated landing (built map, 2 s, gate 4) 0.5 / 1 / 2 / 8 for both noises gave ATE
    56 / 63 / 67 / 278 mm at 346x260 and 74 / 140 / 149 / 1265 mm at 240x180: a stiff model
    rides out the biased registrations better than a loose one follows them. Session 9 (seeds 0-3, 13.42 / 19.00 mm
    with 0.5 / 0.5): angular 0.25 / 0.1 gave 20.16 / 29.99, 72.09 / 419.2 mm; linear 0.25 28.26 mm at 240x180
    (17.77 at 346x260); angular 0.25 with linear 1.0 30.86 / 68.49 mm. Not the model's lag either: the filter's
    twist moved by the true acceleration before every update (an oracle) gave 12.90 / 24.10 mm."""
    linear_acceleration_noise: float = field(default=0.5, metadata={"min": 0.01, "max": 100.0, "step": 0.01, "unit": "m/s^2/sqrt(Hz)"})
    """Spectral density (square root) of the white linear acceleration, m/s^2/sqrt(Hz)."""
    linear_jerk_noise: float = field(default=0.0, metadata={"min": 0.0, "max": 1000.0, "step": 0.5, "unit": "m/s^3/sqrt(Hz)"})
    """Spectral density (square root) of the white jerk driving a world-frame linear acceleration in the state
    (0 = no acceleration state: the constant-velocity model; needs ``velocity_frame`` world), m/s^3/sqrt(Hz).

    A drone that turns a corner accelerates sideways at several m/s^2 (the 3 s simulated landing: 8 m/s^2 for its
    first 0.5 s and again in the turn at 1.4-2 s; the 2 s landing stays below 1 m/s^2). The stiff constant-velocity
    model cannot follow that: its velocity lags by up to 0.9 m/s and the lag turns into a slide along the
    tilt-vs-sideways valley (the pose 35-85 mm off at 0.1-0.3 s while registrations started at the truth land 11 mm
    off). With the acceleration in the state the model follows the manoeuvre, but it also follows the registrations'
    slow biases in steady flight, which the stiff model averages out, so it is off.

    Session 15, ``stpe``, seeds 0-3. The 3 s landing at 346x260, RMS position error of every pose over 0-0.5 /
    0.5-1 / 1-1.5 / 1.5-2 s (``/tmp/s15/stpelong/seg.py``): off 61.1 / 46.9 / 69.0 / 365.3 mm; 1 / 2 / 5 / 10
    gave 31.4 / 46.7 / 184.7 / 724.5, 30.6 / 38.7 / 138.8 / 554.3, 28.9 / 25.0 / 77.3 / 384.4, 26.4 / 24.0 / 84.8 /
    460.9 mm: the first second is 2x better, but the turn (events per update 2000 -> 170-350, 3-7 % of the map
    points on recent events even at the truth) is lost either way, from ~1.4 s; even started from the truth
    (pose and velocity) at 1.0 / 1.3 s the track is 134 / 112 mm off by 1.4 / 1.5 s (seed 0; 133 mm with 10), as
    with any noise, anisotropy or no prior: each registration from the truth lands 13 mm off, and chained they
    drift along the weakly observed direction faster than a model without inertial data can hold. Its ATE (the benchmark's, lost
    poses left out): off 120.1 mm; 1 / 2 / 5 / 10 / 20 / 40 gave 446.9 / 259.0 / 151.0 / 157.7 / 227.5 / 236.6 mm.
    The 2 s landing, mean ATE at 346x260 / 240x180: off 12.40 / 13.80; 1 / 2 / 5 / 10 gave 15.21 / 22.43, 15.72 /
    23.15, 17.86 / 26.11, 19.35 / 30.05 mm (2 with ``initial_acceleration_std`` 0.1: 14.68 mm at 346x260, the 3 s
    segments 52.7 / 32.5 / 130.6 / 574.6 mm). The bundled demo (``evpose track demo_data/landing.h5 --mode stpe``,
    ``evpose eval --align none``, ATE RMSE of the written poses): off 141.1, 5 / 10 82.5 / 89.3 mm."""
    initial_acceleration_std: float = field(default=2.0, metadata={"min": 0.0, "max": 50.0, "step": 0.1, "unit": "m/s^2"})
    """Uncertainty of the initial linear acceleration (zero at the start; ``linear_jerk_noise``), m/s^2."""
    measurement_covariance_scale: float = field(default=1.0, metadata={"min": 0.01, "max": 1000.0, "step": 0.1, "unit": "ratio"})
    """Factor on the registration covariance; > 1 when neighbouring map points' errors are correlated (they are:
    points of one edge see the same events), ratio."""
    measurement_anisotropy: float = field(default=0.2, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "exponent"})
    """Exponent ``g`` that widens the registration covariance along its weak directions before it is fused
    (:func:`stretch_weak_directions`; 0 = the covariance as reported), exponent.

    The reported covariance assumes independent point errors, but the registration's errors are biases shared
    by whole edges (trail, map), and along the tilt-vs-sideways valley they move the pose far more than the
    covariance says: the filter should lean on its motion model there more than elsewhere. In the covariance's
    correlation form (scale-free), eigenvalue ``l`` becomes ``l (l / l_min)^g``. ``stpe``, 2 s landing from
    ground truth, built map, mean ATE of seeds 0-3 at 346x260 / 240x180: 0 / 0.2 / 0.3 / 0.5 gave 15.48 /
    21.53, 14.68 / 21.41, 14.39 / 21.24, 16.02 / 22.66 mm (``prior_residual_sigma`` 0.2); with 0.25, 0 / 0.3
    gave 15.82 / 23.80, 14.86 / 21.60 mm. Scaling the rotation by the altitude instead of the correlation
    form: 0.2 / 0.3 / 0.4 / 0.6 gave 15.43 / 21.30, 15.26 / 20.78, 15.38 / 21.13, 17.38 / 23.25 mm (with
    ``crowded_radius_px`` scaled to 2.08 px at 240x180). A uniform ``measurement_covariance_scale`` of 0.5 / 2 /
    4 gave 16.09 / 23.08, 15.91 / 21.79, 15.37 / 21.89 mm (same crowding). Diagonal covariances are unchanged.
    With ``map_refinement.register_after_updates`` 10: 0 / 0.2 / 0.3 gave 13.60 / 20.06, 13.42 / 19.00, 13.49 /
    18.46 mm, but the bundled demo's camera accelerates at 4-5 m/s^2, which a model leaned on lags: ``stpe`` on
    ``demo_data/landing.h5`` (``--align none``, lost from ~2 s in every case) 126.4 / 140.1 / 161.2 mm ATE RMSE
    (134.9 mm before this session's changes), so 0.2. ``full`` does not use this filter. Session 11, 240x180 with
    the normal-only gradients (seeds 0-3, 16.80 mm at 0.2, before ``edge_offsets``): 0.3 / 0.4 gave 17.23 / 19.00 mm;
    ``prior_residual_sigma`` 0.25 17.29 mm."""
    initial_rotation_std_deg: float = field(default=0.1, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "deg"})
    """Uncertainty of the initial orientation, degrees."""
    initial_translation_std_m: float = field(default=0.005, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "m"})
    """Uncertainty of the initial position, metres."""
    initial_angular_rate_std: float = field(default=0.2, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "rad/s"})
    """Uncertainty of the initial angular rate, rad/s."""
    initial_velocity_std: float = field(default=0.2, metadata={"min": 0.0, "max": 10.0, "step": 0.01, "unit": "m/s"})
    """Uncertainty of the initial velocity, m/s."""
    gate_sigma: float = field(default=4.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """Registrations whose innovation exceeds this Mahalanobis distance are not fused (0 = fuse all), sigma.

    Without a gate the filter follows the registration's slide along the tilt-vs-shift
    valley in the first 80 ms of the simulated landing (only edges across the motion
    fire; the registration lands 2-3 deg off, from the true pose, even on a perfect
    map, with a covariance that claims 0.2 deg): 489 mm ATE on the perfect map; with
    4 sigma, 21 mm. 3 / 4 / 6 sigma: 62 / 63 / 323 mm at 346x260 (acceleration noise 1-2)."""
    prior_in_registration: bool = True
    """Give the registration the prediction as a prior with the filter's predicted covariance.

    (The fused covariance is then the events' alone, but the prior still shapes the
    registration's minimum, so the prediction counts a little twice.) The prior is
    anisotropic: it holds the registration where the events say little (the
    tilt-vs-sideways valley over flat ground) and lets it follow them elsewhere, so
    fewer registrations slide off and get gated. On the simulated landing (2 s, from
    ground truth, ``prior_residual_sigma`` 0.25), mean over five starts (``warmup_ms``
    20-40), this prior with a world-frame velocity against neither (session 2's filter):
    ATE 50.9 / 73.5 mm, ARE 0.77 / 1.14 deg, 2-4 / 21-24 not-OK updates at 346x260
    and 60.6 / 97.2 mm, 0.87 / 1.08 deg, 1-2 / 9-12 at 240x180 (map built at the start
    of session 3); 55.1 / 65.8 mm and 53.9 / 57.6 mm on session 3's builder; on the
    simulator's true edges 17.9 / 18.5 mm and 26 / 28 mm (one start). With a
    body-frame velocity the prior gave 116 / 116 mm (``prior_residual_sigma`` 0.5):
    it needs the world-frame prediction. Taking the prior back out of the registered
    pose before fusing it (no double counting, linearised) gave 68 / 53 / 58 / 54 mm
    on those four cases against 52 / 57 / 46 / 44 mm: on a biased map the second
    count of the prediction is a useful regulariser. On the bundled 4 s demo, whose
    camera accelerates at 4-5 m/s^2, the stiffer model costs accuracy before the track
    is lost at 0.22 s (as before): 71 / 60 mm over 0-0.5 / 0.5-1 s against 61 / 48 mm
    (63 / 47 mm without the double count)."""
    prior_residual_sigma: float = field(default=0.2, metadata={"min": 0.05, "max": 2.0, "step": 0.05, "unit": "TDF"})
    """Typical TDF residual of one point that converts the filter's prior into the registration cost's units
    (``prior_in_registration``; larger = a stiffer prior), TDF units.

    Session 7 (2 s landing, seeds 0-3, mean ATE 346x260 / 240x180, ``crowded_radius_px`` 2.08 px at 240x180,
    no ``measurement_anisotropy``): 0.15 / 0.2 / 0.25 / 0.3 gave 15.92 / 22.06, 15.48 / 21.53, 15.82 / 22.21,
    16.31 / 23.04 mm; with ``measurement_anisotropy`` 0.3 and the default crowding, 0.2 / 0.25 gave 14.39 / 21.24
    and 14.86 / 21.60 mm. Earlier sessions:

    On the simulated landing (``registration.min_inlier_ratio`` 0.05; pinned built map,
    346x260 / 240x180) 0.25 / 0.35 / 0.5 / 0.7 gave 52 / 46 / 57 / 70 mm and
    77 / 82 / 78 / 88 mm ATE; today's built map 32 / 42 / 52 / - and 44 / 44 / 57 / - mm;
    the true edges - / 17 / 14.5 / 20 mm and - / 23 / 23 / 36 mm; the demo's first
    second 81-63 / 96-77 / 128-117 / - mm (0-0.5 s, 0.5-1 s). A stiffer prior suits
    an accurate map and a smooth flight, a weaker one a biased map and a
    manoeuvring camera; run-to-run changes of 10-15 mm come from single slides
    along the tilt-vs-shift valley, so only the trend is meaningful.

    Session 15 (``stpe``, seeds 0-3; 3 s landing ATE with lost poses left out, 2 s landing at 346x260): 0.2 120.07 /
    12.40 mm; 0.05 93.70 / 12.48, 0.1 117.91 / 11.90, 0.15 113.44 / 12.55 mm, and no prior at all
    (``prior_in_registration`` off) 104.60 / 12.20 mm with 8 lost updates. 0.1 further: 240x180 13.80 -> 13.89 mm,
    the bundled demo 141.1 -> 130.7 mm; ``stpe+filter`` 3 s 117.74 -> 115.93, 2 s 12.00 / 13.97 -> 12.24 / 13.85
    mm, demo 150.3 -> 139.4 mm. The 3 s figures move with which seed is lost when (every setting loses the turn at
    1.4-1.5 s); the 2 s ones are within their seed noise: not changed."""
    velocity_frame: VelocityFrame = VelocityFrame.WORLD
    """Frame of the constant linear velocity: world (straight flight while turning) or body (screw motion).

    Alone it changes little on the simulated landing (70.7 / 84.0 mm against 71.2 / 82.3 mm
    at 346x260 / 240x180), but the filter's prior in the registration (``prior_in_registration``)
    only helps with it."""
    weak_gate_sigma: float = field(default=3.0, metadata={"min": 0.0, "max": 100.0, "step": 0.5, "unit": "sigma"})
    """A weak registration (inlier share between ``registration.weak_inlier_ratio`` and ``min_inlier_ratio``) is
    fused only if its innovation is within this Mahalanobis distance of the prediction; otherwise the track is
    lost, sigma. 2 / 3 / 4 gave the same demo track (the registration's prior keeps its innovations small)."""
    max_gated: int = field(default=20, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """After this many registrations in a row were gated out the next one is fused anyway (the model may be
    the one that is wrong), updates."""
    adaptive_noise_max_scale: float = field(default=1.0, metadata={"min": 1.0, "max": 100.0, "step": 0.5, "unit": "ratio"})
    """Largest factor the innovation test may put on both acceleration noises (1 = a fixed motion model), ratio.

    The filter is stiff so that it rides out biased registrations in steady flight, which makes it lag
    a manoeuvre: the innovations then keep pointing the same way. Their whitened running mean against
    their running power (``|mean|^2 / mean |z|^2``: ~``1 / adaptive_noise_window`` for white
    innovations, 1 for a constant bias) measures that consistency; above ``adaptive_noise_threshold``
    the noises are scaled up linearly to this factor at full consistency (at once), and they fall back
    with the window's time constant once the innovations turn white again. The ratio is scale-free on
    purpose: with the filter's prior in the registration (``prior_in_registration``) the registration is
    pulled toward the prediction, so the innovations are small (0.3-0.6 sigma) even while the track
    drifts, and a plain normalised-innovation test (NIS against its chi-square bound) never fires.

    Off by default, measured (``stpe``, all else default): on the bundled demo (4 s, 4-5 m/s^2)
    10 / 0.15 (max scale / threshold) and 4 / 0.3 cut the error before the first loss from 71 / 61 mm
    to 40 / 35 and 55 / 44 mm (0-0.5 / 0.5-1 s), but the loss at 0.22 s stays (the registration's
    inlier-ratio test fails there and on a quarter of the updates even at the true pose: too few
    events) and the looser filter then re-acquires into wrong minima, reporting poses 0.35-0.55 m off
    at 1-2 s (and, with 10, metres off after 2 s) where the fixed model stays lost. On the simulated
    landing (five starts, 346x260 / 240x180) 50.9 / 60.6 mm became 75.4 / 71.2 and 64.6 / 57.4 mm:
    the map's biased registrations also give consistent innovations, which the test cannot tell from
    a lag.

    Session 15, the 3 s landing (8 m/s^2 sideways for its first 0.5 s, then a turn at 1.4-2 s; ``stpe``, seeds
    0-3, 346x260): RMS position error of every pose over 0-0.5 / 0.5-1 / 1-1.5 / 1.5-2 s off 61.1 / 46.9 / 69.0 /
    365.3 mm; 10 / 0.3 35.0 / 26.7 / 57.0 / 216.4, 10 / 0.5 46.6 / 28.9 / 57.7 / 229.4, 10 / 0.6 51.2 / 36.3 / 66.3
    / 273.2, 10 / 0.7 55.2 / 38.5 / 69.1 / 334.6, 20 / 0.6 48.3 / 36.1 / 63.8 / 227.7 mm, and scaling the linear
    noise alone (10 / 0.3) 32.1 / 38.4 / 96.6 / 521.7 mm. The turn is lost in every case. 2 s landing, mean ATE
    at 346x260 (off 12.40 mm): 10 / 0.3 14.18, 10 / 0.5 13.46, 10 / 0.6 12.75, 10 / 0.7 12.27, 20 / 0.6 13.29 mm,
    linear alone 15.10 mm. The two closest, in full (off: ``stpe`` 3 s 120.07 mm ATE (lost poses left out), 2 s
    12.40 / 13.80 mm at 346x260 / 240x180, demo 141.1 mm; ``stpe+filter`` 117.74, 12.00 / 13.97 mm): 10 / 0.7
    ``stpe`` 129.16, 12.27 / 13.81, demo 149.6, ``stpe+filter`` 142.15, 11.91 / 13.87 mm; 10 / 0.6 ``stpe`` 118.52,
    12.75 / 14.59, demo 133.0, ``stpe+filter`` 93.95, 12.39 / 14.20 mm: no setting is better on all of them."""
    adaptive_noise_window: float = field(default=20.0, metadata={"min": 2.0, "max": 1000.0, "step": 1.0, "unit": "updates"})
    """Time constant of the running innovation mean and power (``adaptive_noise_max_scale``), updates."""
    adaptive_noise_threshold: float = field(default=0.3, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Innovation consistency (``|mean|^2 / power``) below which the motion model is left as configured, ratio."""
