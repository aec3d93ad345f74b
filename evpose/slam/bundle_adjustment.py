"""Local bundle adjustment of a map's recent keyframes and their points (gtsam, Huber reprojection factors, LM)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.geometry import pose_jump_depths


@dataclass
class BaReport:
    keyframes: int = 0
    """Keyframes optimised (not counting fixed ones)."""
    points: int = 0
    """Points optimised."""
    initial_error: float = 0.0
    """Total factor-graph error before optimisation."""
    final_error: float = 0.0
    """... and after."""


def local_bundle_adjustment(m: SlamMap, K: np.ndarray, window: int, iterations: int, huber_px: float, n_fixed: int = 1,
                            rotation_priors: dict | None = None, rotation_sigma_rad: float = 1e-3, scale_anchor: float = 0.0,
                            rotation_sigmas_rad: dict | None = None, velocity_sigma_ratio: float = 0.0,
                            rotation_rate_sigma_rad_s: float = 0.0, edge_along_sigma_px: float = 0.0,
                            edge_max_ratio: float = 0.1, max_jump_depths: float = 0.0,
                            attitude_priors: dict | None = None, extra_factors=None) -> BaReport:
    """Optimise the last ``window`` keyframes of ``m`` and the points they see, in place.

    The ``n_fixed`` oldest keyframes of the window (two while the map has only
    its two initial keyframes, fixing the monocular scale) are held by tight
    priors; keyframes outside the window that see the same points contribute
    their observations with fixed poses. Points with fewer than two
    observations are left out. ``rotation_priors`` maps keyframe-id pairs
    ``(a, b)`` to a measured camera rotation ``R_ca_cb`` (3, 3), e.g. from the
    gyro; each adds a between factor of ``rotation_sigma_rad`` on the rotation
    (translation free; ``rotation_sigmas_rad`` may give a pair its own sigma). ``scale_anchor`` > 0 adds a range factor holding the distance between the two oldest
    keyframes of the window at its value before the optimisation, with that sigma relative to the distance: with one
    fixed keyframe the monocular scale is a gauge freedom the solver may slide along.
    ``velocity_sigma_ratio`` > 0 adds constant-velocity factors between consecutive keyframes
    (:mod:`evpose.slam.motion_prior`), that share of the speed as sigma; ``rotation_rate_sigma_rad_s`` > 0 adds
    constant-rotation-rate factors with that sigma, rad/s. ``edge_along_sigma_px`` > 0 gives observations on a straight
    edge of a keyframe MCI (structure-tensor eigenvalue ratio below ``edge_max_ratio``; keyframes that keep their
    ``image8``) that sigma along the edge, pixels: KLT measures only the motion across an edge.
    ``attitude_priors`` maps keyframe ids to (target ``T_wc``, 6x6 covariance): a prior on each free keyframe of the
    window, with a Huber loss at two sigmas (:func:`evpose.slam.room_axes.room_priors`: the rotation from the room's
    axis-aligned edges). ``extra_factors(graph, present, free)`` may add factors on the graph's keyframes (``present``
    the pose variables, ``free`` the optimised ones; :func:`evpose.slam.young_scale.speed_factor_hook`).
    ``max_jump_depths`` > 0 leaves the map as it was when the solution moves a free keyframe's camera centre farther
    than that many median distances of the optimised points from it (:attr:`TrackingConfig.max_jump_depths`).
    """
    import gtsam
    from gtsam.symbol_shorthand import L, X

    if iterations <= 0 or len(m.keyframes) < 2:
        return BaReport()
    kfs = m.keyframes[-window:]
    free_ids = [kf.id for kf in kfs]
    fixed_ids = set(free_ids[: max(n_fixed, 2 if len(m.keyframes) <= 2 else n_fixed)])
    kf_by_id = {kf.id: kf for kf in m.keyframes}
    in_window = set(free_ids)
    pt_ids = sorted({pid for pid, p in m.points.items() if any(k in in_window for k in p.obs)})
    cal = gtsam.Cal3_S2(K[0, 0], K[1, 1], 0.0, K[0, 2], K[1, 2])
    noise = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(huber_px), gtsam.noiseModel.Isotropic.Sigma(2, 1.0))
    tight = gtsam.noiseModel.Isotropic.Sigma(6, 1e-6)
    graph = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    used_kfs: set[int] = set()
    used_pts = []
    tensors: dict = {}
    for pid in pt_ids:
        p = m.points[pid]
        obs = sorted(p.obs.items())
        if len(obs) < 2:
            continue
        used_pts.append(pid)
        values.insert(L(pid), gtsam.Point3(*p.xyz))
        for kid, uv in obs:
            nm = noise
            if edge_along_sigma_px > 0:
                nm = _edge_noise(gtsam, kf_by_id.get(kid), uv, tensors, edge_along_sigma_px, edge_max_ratio, huber_px) or noise
            graph.add(gtsam.GenericProjectionFactorCal3_S2(np.asarray(uv, np.float64), nm, X(kid), L(pid), cal))
            used_kfs.add(kid)
    if not used_pts:
        return BaReport()
    n_free = 0
    for kid in sorted(used_kfs):
        pose = gtsam.Pose3(kf_by_id[kid].T_wc)
        values.insert(X(kid), pose)
        if kid in fixed_ids or kid not in in_window:
            graph.add(gtsam.PriorFactorPose3(X(kid), pose, tight))
        else:
            n_free += 1
    if rotation_priors:
        # Pose3 tangent order is (rotation, translation): a loose translation sigma leaves it to the images.
        sigmas = rotation_sigmas_rad or {}
        for (a, b), R_ab in sorted(rotation_priors.items()):
            if a in used_kfs and b in used_kfs and (a in in_window or b in in_window):
                sig = float(sigmas.get((a, b), rotation_sigma_rad))
                rot_noise = gtsam.noiseModel.Diagonal.Sigmas(np.r_[np.full(3, sig), np.full(3, 1e4)])
                graph.add(gtsam.BetweenFactorPose3(X(a), X(b), gtsam.Pose3(gtsam.Rot3(np.asarray(R_ab, np.float64)), np.zeros(3)), rot_noise))
    if attitude_priors:
        for kid, (T_t, C) in sorted(attitude_priors.items()):
            if kid in used_kfs and kid in in_window and kid not in fixed_ids:
                # Huber at two sigmas: a mislabelled measurement pulls no harder than a fair one.
                nm = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(2.0), gtsam.noiseModel.Gaussian.Covariance(C))
                graph.add(gtsam.PriorFactorPose3(X(kid), gtsam.Pose3(np.asarray(T_t, np.float64)), nm))
    if scale_anchor > 0 and len(free_ids) >= 2 and free_ids[1] not in fixed_ids and free_ids[0] in used_kfs and free_ids[1] in used_kfs:
        a, b = kf_by_id[free_ids[0]], kf_by_id[free_ids[1]]
        d = float(np.linalg.norm(a.T_wc[:3, 3] - b.T_wc[:3, 3]))
        if d > 0:
            graph.add(gtsam.RangeFactorPose3(X(a.id), X(b.id), d, gtsam.noiseModel.Isotropic.Sigma(1, scale_anchor * d)))
    if velocity_sigma_ratio > 0:
        from evpose.slam.motion_prior import add_velocity_factors

        # The keyframe before the window, when it sees the window's points, ties the first free velocity to the past.
        add_velocity_factors(graph, m.keyframes[-(window + 1):], used_kfs, in_window - fixed_ids, velocity_sigma_ratio)
    if rotation_rate_sigma_rad_s > 0:
        from evpose.slam.motion_prior import add_rotation_rate_factors

        add_rotation_rate_factors(graph, m.keyframes[-(window + 1):], used_kfs, in_window - fixed_ids, rotation_rate_sigma_rad_s)
    if extra_factors is not None:
        extra_factors(graph, used_kfs, in_window - fixed_ids)
    params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(int(iterations))
    e0 = graph.error(values)
    try:
        result = gtsam.LevenbergMarquardtOptimizer(graph, values, params).optimize()
    except RuntimeError:
        # An indeterminate system (e.g. a point seen along one ray) leaves the map as it was.
        return BaReport(n_free, len(used_pts), e0, e0)
    moved = [kid for kid in sorted(used_kfs) if kid in in_window and kid not in fixed_ids]
    if max_jump_depths > 0 and used_pts and moved:
        Xw = np.stack([m.points[pid].xyz for pid in used_pts])
        if max(pose_jump_depths(result.atPose3(X(kid)).matrix(), (kf_by_id[kid].T_wc,), Xw) for kid in moved) > max_jump_depths:
            # A solution that flings a keyframe many scene depths away is a diverged one (a pre-IMU-initialisation
            # visual BA moved keyframes 81-127 depths, TrackingConfig.max_jump_depths): keep the map as it was.
            return BaReport(n_free, len(used_pts), e0, e0)
    for kid in moved:
        kf_by_id[kid].T_wc = result.atPose3(X(kid)).matrix()
    for pid in used_pts:
        m.points[pid].xyz = np.asarray(result.atPoint3(L(pid)), np.float64)
    return BaReport(n_free, len(used_pts), e0, graph.error(result))


def _edge_noise(gtsam, kf, uv, tensors: dict, along_px: float, max_ratio: float, huber_px: float):
    """Anisotropic Huber noise for an observation on a straight edge of ``kf``'s MCI (None: not on an edge, or no image)."""
    if kf is None or kf.image8 is None:
        return None
    if kf.id not in tensors:
        img = kf.image8.astype(np.float32)
        gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3)
        gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3)
        tensors[kf.id] = np.stack([cv2.boxFilter(a, -1, (11, 11), normalize=False) for a in (gx * gx, gx * gy, gy * gy)])
    T = tensors[kf.id]
    h, w = T.shape[1:]
    iu, iv = min(max(int(round(uv[0])), 0), w - 1), min(max(int(round(uv[1])), 0), h - 1)
    S = np.array([[T[0, iv, iu], T[1, iv, iu]], [T[1, iv, iu], T[2, iv, iu]]], np.float64)
    ev, V = np.linalg.eigh(S)
    if not ev[1] > 0 or ev[0] >= max_ratio * ev[1]:
        return None
    n, e = V[:, 1], V[:, 0]
    C = np.outer(n, n) + along_px**2 * np.outer(e, e)
    return gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(huber_px), gtsam.noiseModel.Gaussian.Covariance(C))
