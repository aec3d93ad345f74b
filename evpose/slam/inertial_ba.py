"""Inertial local bundle adjustment (gtsam): reprojection factors plus IMU preintegration factors between keyframes.

Runs on maps the IMU initialisation made metric and gravity-aligned (gravity
along -z, gtsam's ``MakeSharedU`` convention). Variables per keyframe of the
window: body pose ``T_world_imu`` and velocity; one gyro/accelerometer bias for
the window. Camera poses are recovered through ``T_cam_imu``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.imu import ImuSamples
from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.inertial import GRAVITY, preintegrated_measurements  # noqa: F401 - re-exported
from evpose.slam.inertial_window_config import InertialWindowConfig
from evpose.slam.velocity_marginal import carried_velocity_noise, store_velocity_covariances


@dataclass
class InertialState:
    """Per-map inertial state kept between optimisations."""

    velocities: dict
    """Keyframe id -> world velocity of the IMU (3,), m/s."""
    bias_acc: np.ndarray
    """Accelerometer bias (3,), m/s^2."""
    bias_gyro: np.ndarray
    """Gyroscope bias (3,), rad/s."""
    velocity_cov: dict = field(default_factory=dict)
    """Keyframe id -> marginal covariance (3, 3) of its velocity in the last inertial BA that held it, (m/s)^2; kept
    only with ``InertialWindowConfig.velocity_marginal`` (:mod:`evpose.slam.velocity_marginal`)."""


def inertial_local_bundle_adjustment(m: SlamMap, state: InertialState, K: np.ndarray, imu: ImuSamples, T_cam_imu: np.ndarray, time_offset_us: int,
                                     window: int, iterations: int, huber_px: float, acc_sigma: float = 0.01, gyro_sigma: float = 0.001,
                                     acc_bias_sigma: float = 0.1, gyro_bias_sigma: float = 0.01,
                                     fill_from_imu: bool = False, velocity_prior_sigma: float = 0.5, min_span_s: float = 0.0,
                                     span_keyframes: int = 4, anchors: InertialWindowConfig | None = None, marginals: bool = False) -> float:
    """Optimise the last ``window`` keyframes (poses, velocities), the window's bias and the points they see, in place.

    The oldest keyframe of the window is held by a tight prior (the IMU fixes scale and
    gravity direction, so one pose suffices), its velocity by one of ``velocity_prior_sigma`` (m/s) at its last
    estimate (``InertialConfig.ba_velocity_prior_sigma``); the bias is held near its last estimate by
    ``acc_bias_sigma`` (m/s^2) and ``gyro_bias_sigma`` (rad/s). When the window spans less than ``min_span_s``
    (keyframes made a few ms apart), up to ``span_keyframes`` older keyframes, thinned in time, extend it back to that
    span (:func:`spanning_window`). ``anchors`` (:class:`evpose.slam.inertial_window_config.InertialWindowConfig`, all
    off by default) add fixed older keyframes, an IMU factor from an older fixed keyframe, a prior on the oldest
    velocity from the map's own keyframe path, the refusal or clamping of a result that rescales the window, and the
    oldest velocity's prior from its marginal covariance in the previous BA (``velocity_marginal``, which ``marginals``
    also turns on for a call without ``anchors``: the full BA after the initialisation). Returns the final graph error
    (nan if skipped or refused).
    """
    import gtsam
    from gtsam.symbol_shorthand import B, L, V, X

    kfs = spanning_window(m.keyframes, window, min_span_s, span_keyframes)
    if iterations <= 0 or len(kfs) < 2:
        return float("nan")
    if fill_from_imu:
        from evpose.slam.inertial_bridge import fill_velocities

        fill_velocities(m.keyframes, state, imu, T_cam_imu, time_offset_us, acc_sigma, gyro_sigma)
    T_cb = np.asarray(T_cam_imu, np.float64)
    T_bc = invert_pose(T_cb)
    body_P_cam = gtsam.Pose3(T_bc)
    ids = [kf.id for kf in kfs]
    in_window = set(ids)
    cal = gtsam.Cal3_S2(K[0, 0], K[1, 1], 0.0, K[0, 2], K[1, 2])
    noise = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(huber_px), gtsam.noiseModel.Isotropic.Sigma(2, 1.0))
    graph = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    bias = gtsam.imuBias.ConstantBias(state.bias_acc, state.bias_gyro)
    values.insert(B(0), bias)
    # The bias may move this much from its last estimate per optimisation: loose priors let the window's bias soak up
    # visual errors (measured: gyro bias estimates of 0.04 rad/s for a true 0.002 on the simulated landing).
    graph.add(gtsam.PriorFactorConstantBias(B(0), bias, gtsam.noiseModel.Diagonal.Sigmas(np.r_[np.full(3, acc_bias_sigma), np.full(3, gyro_bias_sigma)])))
    for i, kf in enumerate(kfs):
        T_wb = kf.T_wc @ T_cb
        values.insert(X(kf.id), gtsam.Pose3(T_wb))
        v = state.velocities.get(kf.id)
        if v is None:
            prev = kfs[i - 1] if i > 0 else None
            v = ((kf.T_wc[:3, 3] - prev.T_wc[:3, 3]) / max((kf.t_us - prev.t_us) / 1e6, 1e-6)) if prev is not None else np.zeros(3)
        values.insert(V(kf.id), np.asarray(v, np.float64))
    graph.add(gtsam.PriorFactorPose3(X(ids[0]), gtsam.Pose3(kfs[0].T_wc @ T_cb), gtsam.noiseModel.Isotropic.Sigma(6, 1e-6)))
    anc = anchors if anchors is not None else InertialWindowConfig()
    v_map = map_velocity(m.keyframes, kfs[0], anc.velocity_span_s) if anc.velocity_span_s > 0 else None
    keep_cov = marginals or anc.velocity_marginal
    if v_map is None and anc.velocity_marginal and ids[0] in state.velocity_cov:
        graph.add(gtsam.PriorFactorVector(V(ids[0]), values.atVector(V(ids[0])),
                                          carried_velocity_noise(state.velocity_cov[ids[0]], anc, velocity_prior_sigma)))
    elif v_map is None:
        graph.add(gtsam.PriorFactorVector(V(ids[0]), values.atVector(V(ids[0])), gtsam.noiseModel.Isotropic.Sigma(3, velocity_prior_sigma)))
    else:  # InertialWindowConfig.velocity_span_s: the velocity the map's own keyframe path has there
        graph.add(gtsam.PriorFactorVector(V(ids[0]), v_map, gtsam.noiseModel.Isotropic.Sigma(3, anc.velocity_sigma or velocity_prior_sigma)))
    fixed = fixed_keyframes(m.keyframes, kfs[0], anc.fixed_keyframes, anc.fixed_span_s) if anc.fixed_keyframes > 0 else []
    for kf in fixed:
        values.insert(X(kf.id), gtsam.Pose3(kf.T_wc @ T_cb))
        graph.add(gtsam.PriorFactorPose3(X(kf.id), gtsam.Pose3(kf.T_wc @ T_cb), gtsam.noiseModel.Isotropic.Sigma(6, 1e-6)))
    fixed_ids = {kf.id for kf in fixed}
    old = next((kf for kf in reversed(m.keyframes) if kf.t_us <= kfs[0].t_us - anc.imu_anchor_s * 1e6), None) if anc.imu_anchor_s > 0 else None
    if old is not None and old.id not in in_window and old.id in state.velocities:
        if old.id not in fixed_ids:
            values.insert(X(old.id), gtsam.Pose3(old.T_wc @ T_cb))
            graph.add(gtsam.PriorFactorPose3(X(old.id), gtsam.Pose3(old.T_wc @ T_cb), gtsam.noiseModel.Isotropic.Sigma(6, 1e-6)))
        values.insert(V(old.id), np.asarray(state.velocities[old.id], np.float64))
        graph.add(gtsam.PriorFactorVector(V(old.id), values.atVector(V(old.id)), gtsam.noiseModel.Isotropic.Sigma(3, velocity_prior_sigma)))
        pim = preintegrated_measurements(imu, old.t_us + time_offset_us, kfs[0].t_us + time_offset_us, bias, acc_sigma, gyro_sigma)
        graph.add(gtsam.ImuFactor(X(old.id), V(old.id), X(ids[0]), V(ids[0]), B(0), pim))
    for a, b in zip(kfs[:-1], kfs[1:]):
        pim = preintegrated_measurements(imu, a.t_us + time_offset_us, b.t_us + time_offset_us, bias, acc_sigma, gyro_sigma)
        graph.add(gtsam.ImuFactor(X(a.id), V(a.id), X(b.id), V(b.id), B(0), pim))
    pts = []
    for pid in sorted(m.points):
        p = m.points[pid]
        obs = [(kid, uv) for kid, uv in sorted(p.obs.items()) if kid in in_window or kid in fixed_ids]
        if len(obs) < 2 or not any(kid in in_window for kid, _ in obs):
            continue
        pts.append(pid)
        values.insert(L(pid), gtsam.Point3(*p.xyz))
        for kid, uv in obs:
            graph.add(gtsam.GenericProjectionFactorCal3_S2(np.asarray(uv, np.float64), noise, X(kid), L(pid), cal, body_P_cam))
    params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(int(iterations))
    try:
        result = gtsam.LevenbergMarquardtOptimizer(graph, values, params).optimize()
    except RuntimeError:
        return float("nan")
    f = 1.0  # InertialWindowConfig.max_scale_change: how much of the result's scale change is undone
    if anc.max_scale_change > 1.0:
        ratio = spread_ratio(np.array([kf.T_wc[:3, 3] for kf in kfs]), np.array([(result.atPose3(X(kf.id)).matrix() @ T_bc)[:3, 3] for kf in kfs]))
        if not (1.0 / anc.max_scale_change <= ratio <= anc.max_scale_change):
            if not anc.clamp_scale:
                return float("nan")  # the window keeps its scale from before
            f = float(np.clip(ratio, 1.0 / anc.max_scale_change, anc.max_scale_change)) / ratio
    c0 = kfs[0].T_wc[:3, 3].copy()  # the fixed first camera: the centre the clamp rescales the window about
    for kf in kfs:
        kf.T_wc = result.atPose3(X(kf.id)).matrix() @ T_bc
        state.velocities[kf.id] = np.asarray(result.atVector(V(kf.id)))
    for pid in pts:
        m.points[pid].xyz = np.asarray(result.atPoint3(L(pid)), np.float64)
    if f != 1.0:
        for kf in kfs:
            kf.T_wc[:3, 3] = c0 + f * (kf.T_wc[:3, 3] - c0)
            state.velocities[kf.id] = f * state.velocities[kf.id]
        for pid in pts:
            m.points[pid].xyz = c0 + f * (m.points[pid].xyz - c0)
    if keep_cov:
        store_velocity_covariances(graph, result, ids, state, f)
    b = result.atConstantBias(B(0))
    state.bias_acc, state.bias_gyro = np.asarray(b.accelerometer()), np.asarray(b.gyroscope())
    return float(graph.error(result))


def spanning_window(keyframes: list, window: int, min_span_s: float, extra: int) -> list:
    """The newest ``window`` keyframes, extended back by at most ``extra`` older ones so the window spans ``min_span_s``.

    The older keyframes are picked at least ``min_span_s / (extra + 1)`` apart (IMU factors then join keyframes tens of
    milliseconds apart, whose preintegrated deltas carry the velocity and scale that a few milliseconds cannot).
    """
    kfs = list(keyframes[-window:])
    if min_span_s <= 0 or extra <= 0 or not kfs or len(keyframes) <= window:
        return kfs
    t_new = kfs[-1].t_us
    span_us = int(min_span_s * 1e6)
    if t_new - kfs[0].t_us >= span_us:
        return kfs
    gap_us = span_us // (extra + 1)
    older = []
    for kf in reversed(keyframes[:-window]):
        ref = older[-1].t_us if older else kfs[0].t_us
        if ref - kf.t_us >= gap_us:
            older.append(kf)
            if len(older) >= extra or t_new - kf.t_us >= span_us:
                break
    return older[::-1] + kfs


def fixed_keyframes(keyframes: list, oldest, count: int, span_s: float) -> list:
    """Up to ``count`` keyframes before ``oldest`` (the window's oldest), at least ``span_s / count`` apart, reaching
    back at most ``span_s`` (:attr:`InertialWindowConfig.fixed_keyframes`), oldest first."""
    gap_us = int(span_s * 1e6) // max(count, 1)
    out = []
    for kf in reversed(keyframes):
        if kf.t_us >= oldest.t_us or kf is oldest:
            continue
        if span_s > 0 and oldest.t_us - kf.t_us > span_s * 1e6 and out:
            break
        ref = out[-1].t_us if out else oldest.t_us
        if ref - kf.t_us >= gap_us:
            out.append(kf)
            if len(out) >= count:
                break
    return out[::-1]


def spread_ratio(before: np.ndarray, after: np.ndarray) -> float:
    """RMS distance of the points ``after`` from their centroid over that of ``before`` (a window's scale change)."""
    b = np.sqrt(np.mean(np.sum((before - before.mean(0)) ** 2, 1)))
    f = np.sqrt(np.mean(np.sum((after - after.mean(0)) ** 2, 1)))
    return float(f / b) if b > 0 else 1.0


def map_velocity(keyframes: list, kf, span_s: float) -> np.ndarray | None:
    """Camera velocity of the map's keyframe path over the ``span_s`` ending at ``kf`` (its position minus that of the
    newest keyframe at least ``span_s`` older, over their time apart), map units per second; None without one."""
    t0 = kf.t_us - span_s * 1e6
    old = next((k for k in reversed(keyframes) if k.t_us <= t0), None)
    if old is None:
        return None
    return (kf.T_wc[:3, 3] - old.T_wc[:3, 3]) / ((kf.t_us - old.t_us) / 1e6)
