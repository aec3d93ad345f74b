"""The real-time pose read out with what the fixed-lag smoother has since learnt about the window's older states.

Option ``FusionConfig.revision_readout_states`` (L, 0 = off) and ``revision_readout_gain`` (g), factor graph only.
When state k is added, each older state k-l of the window (l = 1..L) has two estimates: the one written when it was
the newest (the real-time output at its time) and the smoother's estimate now, which includes the registrations that
came after it. Their difference is that state's *revision*. The read-out adds g times the mean revision of states
k-1..k-L to state k's estimate: positions additively, rotations as a world-frame rotation vector about the camera
centre; the position's component along the camera's optical axis times ``revision_readout_depth_ratio`` more, and
the position correction written is ``revision_readout_position_smoothing`` (a) times this one plus 1 - a times the
previous state's (session 37, below). Causal: only states and registrations up to k enter.

What it is for (issue 7, 240x180): the registrations carry slow errors (a few edges' event offsets, session 33/34),
which the real-time estimate follows and a smoother, fed later registrations that see other edges, partly takes out
(offline 3.09 mm against 5.26 mm in real time). Re-predicting state k from the smoothed state k-L with the IMU gives
state k's own estimate back (the IMU factors tie the window together: within 0.2 mm, measured open loop), so the
smoother's past holds no more than its present; what the present misses is how much the newer registrations revised
the older states, which is correlated with state k's own slow error. A gain above 1 because a revision is only part
of the error the state carried.

Only the written pose changes: the fusion's state, its IMU propagation (the registrations' prior), the tracker's
internal pose and the recorded fusion inputs are untouched, so tracking is bit for bit the same with it on or off.
Cost: L pose reads from the smoother plus L rotation logs per update (below). The IMU-rate poses between updates
(``StepResult.imu_poses``, a debug product the viewer draws) are propagated from the fused states and not moved, so
they sit off the written poses by the read-out's correction (0.2 mm on average at 240x180, session 36, before the
depth ratio).

Measured (session 36, rt36), L 7 and gain 2 against off, `full` from ground truth through the CLI (`evpose track
--config`, `evpose eval --align none`) on the cached 2 s moderate landings and built maps (``/tmp/s36/rt36/run.sh``,
paired per seed):

* 240x180 seeds 0-23: 5.255 -> 5.060 mm (-0.195 +- 0.031, 24 of 24 better), ARE 0.0603 -> 0.0597 deg;
* held-out 24-47: 5.652 -> 5.489 (-0.163 +- 0.035, 21 of 24);
* 240x180 3 s seeds 0-7: 13.512 -> 13.387 (-0.125 +- 0.098, 6 of 8; ARE 0.1113 -> 0.1134 deg);
* 346x260 seeds 0-23: 4.279 -> 4.169 (-0.110 +- 0.024, 20 of 24), ARE 0.0504 -> 0.0498;
* demos landing / landing_fast / landing_dynamic / the dynamic one's static twin (``/tmp/s36/rt36/demo.sh``): 6.899 /
  9.132 / 6.312 / 5.840 -> 6.557 / 8.894 / 6.154 / 5.700 mm (dynamic against static 1.08x either way).

Open-loop replays of the recorded fusion inputs (``/tmp/s36/rt36/revise.py``, 240x180 seeds 0-23, 5.205 mm as
replayed): the revision of the one state 1 / 3 / 5 / 7 back alone at gain 1: -0.042 / -0.117 / -0.125 / -0.143 mm
(at gain 2 7 back alone -0.193, 21 of 24); the mean of 1..7 (what the option does) at gain 1 / 1.5 / 2 / 2.5 / 3: -0.116 / -0.161 / -0.197 / -0.223 / -0.239 (24 / 24 / 24 / 22 / 21 of 24 better); a
21-state window, L 10 / 20 at gain 1: -0.140 / -0.167 (more cost, no better); held-out 24-47 at L 7 gain 2 / 3:
-0.175 / -0.206; 346x260 L 7 gain 1 / 2 / 3: -0.072 / -0.117 / -0.135. Re-predicting state k from the smoothed
state k-L through the IMU (``repredict.py``, seeds 0-5): +0.08 (L 5) to +0.14 mm (L 10-40): the IMU factors tie the
window together, so that gives back state k's own estimate (within 0.2 mm).
Closing the loop (``FusionConfig.revision_readout_prior``: the tracker's pose and the next registration's predicted
start moved by the read-out's correction, CLI, 240x180 seeds 0-23): 5.060 -> 5.113 mm against the read-out alone
(+0.054 +- 0.035, 8 of 24 better), so off: a registration pulled towards the corrected prior feeds the fusion a
little of the correction back, and the next revision is made against it.
Cost (``cost.py``, seed 0's inputs replayed, load ~10): the read-out 0.19 ms median per update (p99 0.48), the
fusion update 0.90 -> 1.07 ms median.

Session 37 (ar37, scripts in ``/tmp/s37/ar37/``): depth and smoothing. Open-loop replays of main's recorded fusion
inputs (``feat.py`` stores each update's fused pose and the revisions of its 7 older states; 240x180 2 s seeds
0-23 / held-out 24-47 / 346x260 0-23) with the correction rebuilt offline, paired against this read-out:

* Per camera axis, the least-squares gain of the mean revision (``ana4.py``) is rotation 4.0 / 2.8 / 0.5, 3.4 / 2.3
  / 0.1, 2.3 / 3.8 / 1.2 (x / y / z, one line per set) and position 1.9 / 3.4 / 6.2, 1.0 / 3.1 / 6.5, 3.3 / 2.7 /
  4.1: the revision along the optical axis (depth, which the registrations observe least) is the smaller part of
  its error. Depth gain 3 / 3.5 / 4 / 4.5 / 5 (``ana6.py``): -0.046 / -0.064 / -0.079 / -0.091 / -0.100 mm on seeds
  0-23 (20 / 20 / 18 / 18 / 18 of 24 better), held-out -0.050 / -0.070 / -0.088 / -0.101 / -0.112, 346x260 -0.014 /
  -0.018 / -0.019 / -0.018 / -0.014: ``revision_readout_depth_ratio`` 2 (gain 4). World z instead of the optical
  axis: the same within 0.004 mm. A full 6x6 gain matrix fitted on seeds 0-23 took -0.37 mm off held-out but
  +0.03 at 346x260 (its cross terms differ between the sensors): not used.
* The corrections jitter from update to update: with the read-out the RTE (per frame) is 0.518 mm against 0.236
  without (346x260 0.310 / 0.163; the EKF 0.235 / 0.159), and depth ratio 2 alone makes it 0.679. A causal
  exponential average of the position correction (``revision_readout_position_smoothing``, ``ana8.py``, ``ana9.py``,
  depth ratio 2, alpha 0.7 / 0.5 / 0.3 / 0.2 / 0.1): ATE -0.079 / -0.073 / -0.059 / -0.041 / -0.000 mm with RTE 0.517 /
  0.434 / 0.360 / 0.324 / 0.289 on seeds 0-23; a trend term (Holt) or gain 2.3 trade the same way. Averaging the
  rotation correction too (alpha 0.5) cost ARE +0.00007 deg on all three sets (0 of 24 better), so rotation is left.
* Rotation: a gain of 0 / 1 / 3 / 4 / 6 instead of 2: ARE +0.00066 / +0.00020 / +0.00004 / +0.00034 / +0.00163
  deg (seeds 0-23); per-axis or cross-axis rotation gains at most -0.0001 on held-out seeds; revisions of 6-20 older
  states in a 14- or 21-state window (``ana5.py``) no better in ATE or ARE. The rotation part of this read-out is
  worth -0.0007 / -0.0005 / -0.0006 deg (sets as above) against none, and that is all of the graph's lead over the
  EKF in rotation: the graph without it and the EKF have the same rotation error per axis, slow (0.2 s centred
  mean) and fast (``diag1.py``, CLI outputs of seeds 0-11: 240x180 0.0397 / 0.0299 / 0.0235 against 0.0396 / 0.0297
  / 0.0236 deg slow), 95 % of it slower than 0.2 s and growing through the landing; a batch smoother over the whole
  run gets 0.044 deg against 0.060 online at 240x180 (0.042 / 0.048 at 346x260, ``diag2.py``): what would remove it
  is in later registrations. The registration covariance's rotation block x0.2 / 0.6 / 1.6 / 5 (cross terms by the
  square root, open loop, ``sweep1.sh``, ``cmpt.py``) gave ARE +0.026 / +0.006 / +0.001 / +0.041 deg, the gyroscope
  noise density x0.3 / x3 or bias random walk x0.2 / x5 within 0.0002 deg.

CLI (``run.sh``, ``cmp.py``; depth ratio 2 and smoothing 0.5 against session 36's defaults, ``/tmp/s36/rt36/out/ro7g2``;
tag ``dr2s5``): 240x180 seeds 0-23 5.060 -> 4.984 mm (-0.076 +- 0.025, 18 of 24 better), held-out 24-47 5.489 ->
5.411 (-0.078 +- 0.026, 17 of 24), 346x260 4.169 -> 4.162 (-0.007 +- 0.014, 9 of 24), 240x180 3 s seeds 0-7 13.387 ->
13.392 (+0.005 +- 0.060, 4 of 8), demos (``demo.sh``) landing / landing_fast / landing_dynamic / its static twin
6.557 / 8.894 / 6.154 / 5.700 -> 6.573 / 8.908 / 6.133 / 5.699 mm. The ratio cost in the first 0.5 s (per 0.25 s
bin, ``bins.py``: 0.25-0.5 s worse on 31 of 48 seeds; replayed first 0.5 s +0.006 mm, ``ana10.py``) and on the
quick bench's 0.5 s runs (``evpose bench --suite quick``, ATE mean landing / landing_slow / landing_fast 7.231 /
5.852 / 11.744 -> 7.553 / 5.911 / 11.520 mm with the ratio alone), while the registrations are widened
(``registration_startup_s``), so it applies after that (:func:`depth_ratio`; tag ``gated``, the defaults): 240x180
seeds 0-23 5.060 -> **4.982** mm (-0.078 +- 0.024, 18 of 24), held-out 5.489 -> **5.410** (-0.080 +- 0.026, 18 of
24), 346x260 4.169 -> 4.161 (-0.008 +- 0.014, 12 of 24), 3 s 13.387 -> 13.392 (+0.005 +- 0.060, 4 of 8), demos 6.556
/ 8.880 / 6.131 / 5.697 mm, the quick bench's 0.5 s runs 7.283 / 5.878 / 11.813 mm (the smoothing's lag: +0.05 /
+0.03 / +0.07); ARE unchanged to the last digit (rotation is not touched); RTE 0.518 -> 0.395, 0.520 -> 0.398, 0.310
-> 0.263, 0.883 -> 0.759 mm (every seed better), demos 0.385 / 0.472 / 0.333 / 0.323 -> 0.345 / 0.408 / 0.296 /
0.278. Tracking is the same bit for bit, so these differences are the written poses' alone, not closed-loop chaos.
Against the EKF (``--fusion ekf``, ``ekf.sh``, ``cmpekf.py``; 240x180 seeds 0-47 and 346x260 0-23, 72 pairs): ATE
4.851 against 5.085 mm (-0.235 +- 0.045, 56 of 72 better), ARE 0.0574 against 0.0583 deg (-0.0010 +- 0.0005, 44 of
72), RTE 0.352 against 0.214 mm (0 of 72: the read-out's corrections still jitter more than the EKF's estimate).
Cost (``cost.py`` 346x260, seed 0's inputs replayed, alternated, load ~8.6): the read-out 0.078 -> 0.084 ms median
per update, the fusion update 0.512 -> 0.513 ms.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.core.se3_kernels import so3_log
from evpose.fusion.startup import in_startup


@nb.njit(cache=True)
def _mean_revision(now_imu, T_imu_cam, then, out):
    """``out`` (6,) := the mean over states ``s`` of (``Log(R_now R_then^T)``, ``p_now - p_then``) of the camera poses
    ``now_imu[s] T_imu_cam`` and ``then[s]`` ((n, 4, 4) each): the read-out's loop in one call (session 43; it was
    ~9 us of small numpy products and gtsam calls per state, now ~0.1; equal to rounding, ~1e-16)."""
    n = now_imu.shape[0]
    for i in range(6):
        out[i] = 0.0
    Rn = np.empty((3, 3))
    R = np.empty((3, 3))
    w = np.empty(3)
    for s in range(n):
        A = now_imu[s]
        for i in range(3):
            for j in range(3):
                Rn[i, j] = A[i, 0] * T_imu_cam[0, j] + A[i, 1] * T_imu_cam[1, j] + A[i, 2] * T_imu_cam[2, j]
            p = A[i, 0] * T_imu_cam[0, 3] + A[i, 1] * T_imu_cam[1, 3] + A[i, 2] * T_imu_cam[2, 3] + A[i, 3]
            out[3 + i] += p - then[s, i, 3]
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, 0] * then[s, j, 0] + Rn[i, 1] * then[s, j, 1] + Rn[i, 2] * then[s, j, 2]
        so3_log(R, w)
        for i in range(3):
            out[i] += w[i]
    for i in range(6):
        out[i] /= n


def revised_pose(gtsam, T_world_cam: np.ndarray, rotation: np.ndarray, position: np.ndarray, gain: float,
                 depth_ratio: float = 1.0) -> np.ndarray:
    """``T_world_cam`` moved by ``gain`` times a (rotation vector, position) revision: rotation about the camera centre
    in the world frame, position added; the position revision's component along the camera's optical axis (of
    ``T_world_cam``) times ``depth_ratio`` more (``FusionConfig.revision_readout_depth_ratio``)."""
    out = np.array(T_world_cam, np.float64, copy=True)
    out[:3, :3] = np.asarray(gtsam.Rot3.Expmap(gain * rotation).matrix(), np.float64) @ out[:3, :3]
    step = gain * position
    if depth_ratio != 1.0:
        axis = np.asarray(T_world_cam, np.float64)[:3, 2]  # the fused pose's optical axis in the world (unit)
        step = step + (depth_ratio - 1.0) * float(axis @ step) * axis
    out[:3, 3] += step
    return out


def readout_pose(fusion, T_world_cam: np.ndarray, previous=None) -> np.ndarray | None:
    """The revised camera pose of ``fusion``'s newest state (a :class:`~evpose.fusion.factor_graph.FactorGraphFusion`
    whose ``history`` already holds that state), or None while fewer than ``revision_readout_states`` older states
    are in the window (the start, and after each ``initialize``). ``previous``: the state before it (a
    :class:`~evpose.fusion.state.FusedState` or None), whose written correction
    ``FusionConfig.revision_readout_position_smoothing`` averages with the new one."""
    c = fusion.config
    n = min(int(c.revision_readout_states), int(c.window_states) - 1)  # older states are marginalised
    if n <= 0 or fusion.index < n or len(fusion.history) < n + 1:
        return None
    gtsam = fusion._gtsam
    # Each state's revision is (Log(R_now R_then^T) world rad, p_now - p_then m) of its camera poses now and as written;
    # the smoother's estimates are read here, the revisions and their mean taken in one compiled call.
    estimate = fusion.smoother.calculateEstimatePose3
    key = fusion._keys(fusion.index)[0]
    now, then = np.empty((n, 4, 4)), np.empty((n, 4, 4))
    for lag, written in enumerate(written_poses(fusion, n)):
        now[lag] = estimate(key - lag - 1).matrix()
        then[lag] = written
    mean = np.empty(6)
    _mean_revision(now, fusion.extrinsic.T_imu_cam, then, mean)
    rotation, position = mean[:3], mean[3:]
    out = revised_pose(gtsam, T_world_cam, rotation, position, float(c.revision_readout_gain), depth_ratio(fusion))
    return smoothed_position(out, T_world_cam, previous, float(c.revision_readout_position_smoothing))


def written_poses(fusion, n: int) -> list[np.ndarray]:
    """The camera poses (4, 4) the ``n`` states before ``fusion``'s newest were written with, newest first.

    Each is a pure function of its history entry's NavState (immutable), so it is computed once, when the state is
    first one back, and kept in ``fusion.readout_written`` (keyed by the NavState's id, which the entry's reference
    keeps unique; emptied by the fusion's ``_reset``, so a restore recomputes the same values): one pose conversion per
    update instead of ``n``. Session 40 (``/tmp/s40/lt40/rdbench.py``: both read-outs on the same state at every update
    of ``full`` 346x260 seed 0, order alternated, outputs equal, load ~8): 122-126 -> 114-117 us median per update.
    """
    cache = fusion.readout_written
    kept = {}
    out = []
    for lag in range(1, n + 1):
        nav = fusion.history[-1 - lag][1]
        hit = cache.get(id(nav))
        if hit is None or hit[0] is not nav:
            hit = (nav, fusion.extrinsic.cam_pose(nav.pose().matrix()))
        kept[id(nav)] = hit
        out.append(hit[1])
    fusion.readout_written = kept
    return out


def depth_ratio(fusion) -> float:
    """``FusionConfig.revision_readout_depth_ratio`` for ``fusion``'s newest state, or 1 while the registrations are
    widened after the start (within ``registration_startup_s`` of it, as
    :func:`~evpose.fusion.startup.in_startup`): then the depth revisions do not follow the error the same way
    (session 37, the first 0.5 s at 240x180, replayed: +0.006 mm with the ratio there, -0.006 without; the quick
    bench's 0.5 s landing +0.32 mm)."""
    c = fusion.config
    return 1.0 if in_startup(c, fusion.start_us, fusion.history[-1][0]) else float(c.revision_readout_depth_ratio)


def smoothed_position(out: np.ndarray, T_world_cam: np.ndarray, previous, alpha: float) -> np.ndarray:
    """``out`` (the read-out of ``T_world_cam``, (4, 4), changed in place) with its position correction replaced by a
    causal exponential average: ``alpha`` x this one + (1 - ``alpha``) x the previous state's written correction
    (``previous.readout_T_world_cam - previous.T_world_cam``; none after a start or while ``previous`` had no
    read-out: then this one alone). Rotation untouched (``FusionConfig.revision_readout_position_smoothing``)."""
    if alpha >= 1.0 or previous is None or previous.readout_T_world_cam is None:
        return out
    last = previous.readout_T_world_cam[:3, 3] - previous.T_world_cam[:3, 3]
    out[:3, 3] = T_world_cam[:3, 3] + alpha * (out[:3, 3] - T_world_cam[:3, 3]) + (1.0 - alpha) * last
    return out


def moved_like(T: np.ndarray, T_from: np.ndarray, T_to: np.ndarray) -> np.ndarray:
    """``T`` (4, 4) moved as ``T_from`` was moved to ``T_to``: rotated by ``R_to R_from^T`` about its own centre, shifted by
    ``p_to - p_from`` (``FusionConfig.revision_readout_prior``)."""
    out = np.array(T, np.float64, copy=True)
    out[:3, :3] = (T_to[:3, :3] @ T_from[:3, :3].T) @ out[:3, :3]
    out[:3, 3] += T_to[:3, 3] - T_from[:3, 3]
    return out
