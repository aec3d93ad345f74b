"""Local mapping: keyframe decision and insertion, triangulation of new points, point culling.

Feature associations come from KLT tracks (one track id per key point), not
descriptors, so a map point is tied to the track that created it.
"""

from __future__ import annotations

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import TrackingConfig
from evpose.slam.geometry import good_triangulation, triangulate


def need_keyframe(m: SlamMap, tr_ids: np.ndarray, tr_uv: np.ndarray, n_tracked_points: int, cfg: TrackingConfig) -> bool:
    """The paper's heuristics: tracked map points fell below a share of the last keyframe's, or key points moved far."""
    last = m.keyframes[-1]
    point_tracks = _point_tracks(m)  # once: a set per key point made this quadratic
    n_last = sum(1 for tid in last.obs if tid in point_tracks)
    if n_last and n_tracked_points < cfg.keyframe_tracked_ratio * n_last:
        return True
    common = [(last.obs[t], uv) for t, uv in zip(tr_ids.tolist(), tr_uv) if t in last.obs]
    if not common:
        return True
    disp = np.median([np.linalg.norm(a - b) for a, b in common])
    return bool(disp > cfg.keyframe_displacement_px)


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

    ``predicted``: ``kf`` sits at a pose no image placed (a coast's prediction), where the pair gate of
    ``coast_pair_translation_ratio`` applies instead of ``min_pair_translation_ratio``."""
    by_kf: dict[int, list[int]] = {}
    for tid in sorted(kf.obs):
        if tid in track_to_point:
            continue
        for old in m.keyframes[:-1]:
            if tid in old.obs:
                by_kf.setdefault(old.id, []).append(tid)
                break
    ratio = cfg.coast_pair_translation_ratio if predicted else cfg.min_pair_translation_ratio
    z_med = _median_depth(m, kf, track_to_point) if cfg.min_pair_parallax_deg > 0 or ratio > 0 else None
    for old_id, tids in sorted(by_kf.items()):
        old = m.keyframe(old_id)
        if z_med is not None and np.degrees(np.linalg.norm(kf.T_wc[:3, 3] - old.T_wc[:3, 3]) / z_med) < cfg.min_pair_parallax_deg:
            # Too short a baseline for the scene depth: every track's parallax is near the per-point threshold, and the
            # ones whose noise pushes them over it come out too near. Wait for a later keyframe with a wider baseline.
            continue
        if z_med is not None and ratio > 0 and _rotation_dominated(old.T_wc, kf.T_wc, z_med, ratio):
            continue
        uv1 = np.array([old.obs[t] for t in tids])
        uv2 = np.array([kf.obs[t] for t in tids])
        X = triangulate(K, invert_pose(old.T_wc), invert_pose(kf.T_wc), uv1, uv2)
        good = good_triangulation(K, old.T_wc, kf.T_wc, uv1, uv2, X, 2.0 * cfg.reprojection_threshold_px, cfg.min_triangulation_deg)
        between = [b for b in m.keyframes if old.id < b.id < kf.id] if cfg.intermediate_observations else []
        for k in np.flatnonzero(good):
            tid = tids[k]
            obs = {old.id: uv1[k], kf.id: uv2[k]}
            for b in between:
                uv = b.obs.get(tid)
                if uv is not None and _reprojects(K, b.T_wc, X[k], uv, 2.0 * cfg.reprojection_threshold_px):
                    obs[b.id] = uv
            m.points[next_point_id] = MapPoint(next_point_id, X[k].copy(), dict(sorted(obs.items())), tid, kf.id)
            track_to_point[tid] = next_point_id
            next_point_id += 1
    return next_point_id


def _rotation_dominated(T_a: np.ndarray, T_b: np.ndarray, z_med: float, ratio: float) -> bool:
    """The pair's baseline over the median depth (the translation's image flow, rad) is below ``ratio`` times its
    rotation angle (rad): depths triangulated from it carry the pair's rotation error divided by a small parallax."""
    R = T_a[:3, :3].T @ T_b[:3, :3]
    rot = float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))
    return float(np.linalg.norm(T_b[:3, 3] - T_a[:3, 3])) / z_med < ratio * rot


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


def cull_points(m: SlamMap, K: np.ndarray, track_to_point: dict[int, int], cfg: TrackingConfig) -> int:
    """Remove points behind a keyframe or reprojecting badly, and young points few keyframes confirmed; returns how many."""
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
