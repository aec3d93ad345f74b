"""Re-initialising a young event-only map's structure once its baseline has grown (off by default).

Every indoor event-only map starts from a two-view solution over a few millimetres of baseline (see
:mod:`evpose.slam.initialization`), and the local bundle adjustments that follow carry its error forward. Two ways of
re-estimating the structure later, both keeping the map, its point ids, its tracks and its gauge, so that tracking
carries on from the newest keyframe without a break (per-MCI poses follow their reference keyframes,
:meth:`SlamMap.trajectory`, and the motion model's poses are re-read from them):

- ``TWO_VIEW``: solve the two-view problem again between the first keyframe and the newest one still sharing
  ``min_common`` matches with it (map points both see, plus tracks both followed), keep the pair's distance, triangulate
  the points from that pair, place every other keyframe by PnP on them, re-triangulate the rest from their widest pair,
  bundle-adjust all keyframes.
- ``RETRIANGULATE``: keep the poses; place every point at the triangulation from the two of its keyframes farthest
  apart (optionally followed by that bundle adjustment).

Measured (session 16, simulated indoor room 3 s at 346x260, event-only, scale-aligned ATE % of the distance; defaults:
seeds 0-7 7.39 %, 0-11 8.06 %, 0-19 8.75 %; seeds 12-19 recorded for this in ``/tmp/s16/reinit9/sim``, scripts
there too):

- Tracks die within 2-3 keyframes, so the first keyframe shares only 10-20 matches with any keyframe past the third,
  and those matches' parallax left after the best pure rotation is 0.2-1.0 deg (the room's walls are near-planar).
  ``TWO_VIEW`` over such a pair is no better than the chain of PnP and local BA it replaces: translation direction
  26-60 deg off against the chain's 11-16 deg on four of five maps (one map: 101 -> 26 deg). ``baseline_ratio`` 3,
  ``min_common`` 15: seeds 0-7 7.39 -> 8.48 %.
- A full BA of each map at the end of the run (``/tmp/s15/indooreo/gba.py``): seeds 0-3 7.26 -> 8.77 % (one fixed
  keyframe), 9.53 % (plus the scale anchor), 9.60 % (two fixed); every map got worse: the keyframe observations
  themselves carry the bias, and a better fit of them is no better trajectory.
- ``RETRIANGULATE``, ``baseline_ratio`` 3, no BA: seeds 0-19 8.75 -> 7.85 %, paired -0.90 +- 0.60 points (11 better, 8
  worse, one unchanged), tracked at least 84.1 % (as before); the map re-triangulated first (earlier maps identical)
  9.15 -> 8.50 % (9 better, 5 worse). Landing event-only seeds 0-23 2.78 -> 2.67 %, -0.11 +- 0.39 (13 better, 11
  worse), within 2 % 13 -> 12 of 24 (seeds 0-11 2.37 -> 2.51 %, 7 of 12 either way). The indoor gain did not survive a
  neutral perturbation: with ``TrackingConfig.ba_huber_px`` 2.1, seeds 0-19 8.73 -> 9.45 %, +0.72 +- 0.53 (9 better,
  11 worse; the map re-triangulated first 9.25 -> 9.78 %); over the 40 paired runs -0.09 +- 0.42 (20 better, 19
  worse). Three times (at ratios 3, 6, 12): seeds 0-19 8.24 %, -0.51 +- 0.68 (10 better, 9 worse). CPU per MCI
  unchanged (median of the per-run medians, seeds 0-7: 15.5 -> 15.7 ms, the re-triangulation itself 4-29 ms once
  per map; 8-105 ms with the BA below). Hence off.
- ``RETRIANGULATE`` at 4 keyframes (``keyframes`` 4) instead: indoor 0-19 7.82 %, -0.93 +- 0.52 (14 better, 6 worse;
  seed 18 tracked 76.8 %), landing 0-11 2.37 -> 2.98 %, +0.61 +- 0.36 (5 better, 7 worse).
- ``RETRIANGULATE`` at ratio 2 / 5 (no BA), seeds 0-11: -0.40 +- 0.83 / -0.37 +- 0.67; ratio 3 with the 20-iteration BA:
  seeds 0-11 8.06 -> 7.67 % (-0.40 +- 0.67); with constant-velocity (0.2) and rotation-rate (40 deg/s) factors in that BA
  7.61 % (-0.45 +- 0.91, 5 better, 6 worse); three times (at ratios 3, 6, 12) with the BA, seeds 0-7 7.41 %.
- Re-picking the first pair's homography decomposition at the third keyframe by that keyframe's PnP reprojection error
  (prototype ``/tmp/s16/reinit9/threeview.py``, seeds 0 and 3): the errors of the candidates are alike (0.4-1.4 px,
  within 0.4 px of each other), and over 13-16 mm of baseline every candidate's translation can be wrong (seed 3's last
  map: 91-101 deg off against the truth for all three): no decomposition is there to pick.

Each run re-draws every later map (a change of one map's trajectory changes when the next map starts), so single
seeds swing by +-3 points either way; the figures above are the paired means over all seeds.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.geometry import good_triangulation, triangulate
from evpose.slam.init_parallax import rotation_compensated_parallax_deg

if TYPE_CHECKING:
    from evpose.slam.config import InitializationConfig, TrackingConfig


class RestructureMethod(str, enum.Enum):
    """How a young map's structure is re-estimated."""

    TWO_VIEW = "two-view"
    """Two-view solution between the first keyframe and the chosen one, PnP of the others, re-triangulation, BA."""
    RETRIANGULATE = "retriangulate"
    """Keep the keyframe poses; every point from the widest pair of keyframes that saw it, then BA."""


@dataclass
class RestructureConfig:
    """When and how a young event-only map is re-initialised from a wide-baseline keyframe pair."""

    baseline_ratio: float = field(default=0.0, metadata={"min": 0.0, "max": 50.0, "step": 0.5, "unit": "ratio"})
    """Re-initialise once the chosen keyframe (``TWO_VIEW``: the newest sharing ``min_common`` matches with the map's
    first keyframe; ``RETRIANGULATE``: the newest) lies this many times farther from the first keyframe than the second
    keyframe does (0 disables), ratio. See the module docstring for the measured settings."""
    keyframes: int = field(default=0, metadata={"min": 0, "max": 100, "step": 1, "unit": "keyframes"})
    """Re-initialise (``RETRIANGULATE`` only) once the map has this many keyframes whatever its baseline (0: never);
    each further time needs twice as many, keyframes."""
    method: RestructureMethod = RestructureMethod.RETRIANGULATE
    """How the structure is re-estimated (``TWO_VIEW`` measured worse, see the module docstring)."""
    min_common: int = field(default=30, metadata={"min": 8, "max": 500, "step": 1, "unit": "matches"})
    """``TWO_VIEW``: matches the first keyframe and the chosen one must share, matches."""
    max_keyframes: int = field(default=20, metadata={"min": 3, "max": 200, "step": 1, "unit": "keyframes"})
    """Maps with more keyframes are no longer young and are left alone, keyframes."""
    times: int = field(default=1, metadata={"min": 1, "max": 10, "step": 1, "unit": "times"})
    """How often a map may be re-initialised; each further time needs twice the previous baseline ratio, times."""
    ba_iterations: int = field(default=0, metadata={"min": 0, "max": 100, "step": 1, "unit": "iterations"})
    """Levenberg-Marquardt iterations of a bundle adjustment over all keyframes afterwards (0: none; 20 measured no
    better, see the module docstring), iterations."""
    ba_huber_px: float = field(default=2.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Huber threshold of that bundle adjustment's reprojection factors, pixels."""
    velocity_prior: float = field(default=0.0, metadata={"min": 0.0, "max": 2.0, "step": 0.05, "unit": "ratio"})
    """Constant-velocity factors in that bundle adjustment, sigma as a share of the speed (0: none), ratio."""
    rotation_rate_prior_deg_s: float = field(default=0.0, metadata={"min": 0.0, "max": 200.0, "step": 1.0, "unit": "deg/s"})
    """Constant-rotation-rate factors in that bundle adjustment, sigma (0: none), deg/s."""
    scale_anchor: float = field(default=0.02, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "ratio"})
    """Sigma of the range factor holding the first two keyframes' distance in that bundle adjustment, share of it."""


@dataclass
class RestructureReport:
    """Outcome of one re-initialisation attempt."""

    ok: bool
    reason: str = ""
    pair: tuple[int, int] = (0, 0)
    """Keyframe ids of the pair the map was re-initialised from."""
    parallax_deg: float = 0.0
    points: int = 0
    """Points placed after the re-initialisation."""


def _common(a, b) -> list[int]:
    return sorted(set(a.obs) & set(b.obs))


def _seen(p, kf) -> np.ndarray | None:
    """Pixel of point ``p`` in keyframe ``kf``: its own observation, else the keyframe's of the point's track (a point
    triangulated after the keyframe was made has no observation there, though its track was already followed)."""
    uv = p.obs.get(kf.id)
    return uv if uv is not None else kf.obs.get(p.track_id)


def _pair_matches(m: SlamMap, a, b) -> tuple[np.ndarray, np.ndarray]:
    """Matched pixels of keyframes ``a`` and ``b``: map points both see, and tracks both followed that carry no such point."""
    p1, p2, tracks = [], [], set()
    for _, p in sorted(m.points.items()):
        ua, ub = _seen(p, a), _seen(p, b)
        if ua is not None and ub is not None:
            p1.append(ua), p2.append(ub), tracks.add(p.track_id)
    for t in _common(a, b):
        if t not in tracks:
            p1.append(a.obs[t]), p2.append(b.obs[t])
    return np.array(p1, np.float64).reshape(-1, 2), np.array(p2, np.float64).reshape(-1, 2)


def restructure_due(m: SlamMap, K: np.ndarray, cfg: RestructureConfig) -> int | None:
    """Index of the keyframe to re-initialise against when the map is young and its baseline wide enough, else None."""
    if (cfg.baseline_ratio <= 0 and cfg.keyframes <= 0) or m.restructured >= cfg.times or not 3 <= len(m.keyframes) <= cfg.max_keyframes or m.imu_initialised:
        return None
    kf0 = m.keyframes[0]
    d1 = float(np.linalg.norm(m.keyframes[1].T_wc[:3, 3] - kf0.T_wc[:3, 3]))
    need = cfg.baseline_ratio * 2.0**m.restructured * d1
    if cfg.method is RestructureMethod.RETRIANGULATE:
        d = float(np.linalg.norm(m.keyframes[-1].T_wc[:3, 3] - kf0.T_wc[:3, 3]))
        wide = cfg.baseline_ratio > 0 and d >= need
        old = cfg.keyframes > 0 and len(m.keyframes) >= cfg.keyframes * 2**m.restructured
        return len(m.keyframes) - 1 if wide or old else None
    if cfg.baseline_ratio <= 0:
        return None
    for j in range(len(m.keyframes) - 1, 1, -1):
        if len(_pair_matches(m, kf0, m.keyframes[j])[0]) >= cfg.min_common:
            d = float(np.linalg.norm(m.keyframes[j].T_wc[:3, 3] - kf0.T_wc[:3, 3]))
            return j if d >= need else None
    return None


def restructure_map(m: SlamMap, K: np.ndarray, j: int, cfg: RestructureConfig, icfg: InitializationConfig, tc: TrackingConfig,
                    track_to_point: dict[int, int], seed: int = 0) -> RestructureReport:
    """Re-initialise ``m`` from its first keyframe and keyframe index ``j``; in place on success, untouched on failure."""
    # Imported here: both import SlamConfig's module, which imports this one for RestructureConfig.
    from evpose.slam.initialization import initialize_two_view
    from evpose.slam.tracking import estimate_pose

    kfs = m.keyframes
    kf0, kfj = kfs[0], kfs[j]
    if cfg.method is RestructureMethod.RETRIANGULATE:
        poses = {kf.id: kf.T_wc for kf in kfs}
        for p in m.points.values():
            X = _widest_pair_point(K, p.obs, poses, tc)
            if X is not None:
                p.xyz = X
        return _finish(m, K, cfg, (kf0.id, kfj.id), 0.0)
    p1, p2 = _pair_matches(m, kf0, kfj)
    par = rotation_compensated_parallax_deg(K, p1, p2)
    res = initialize_two_view(K, p1, p2, icfg, seed)
    if not res.ok:
        return RestructureReport(False, f"two-view: {res.reason}", (kf0.id, kfj.id), par)
    # Gauge: the first keyframe keeps its pose and the pair keeps its current distance.
    d_now = float(np.linalg.norm(kfj.T_wc[:3, 3] - kf0.T_wc[:3, 3]))
    T_rel = res.T_wc2.copy()
    d_new = float(np.linalg.norm(T_rel[:3, 3]))
    if not (d_now > 0 and d_new > 0):
        return RestructureReport(False, "degenerate baseline", (kf0.id, kfj.id), par)
    T_rel[:3, 3] *= d_now / d_new
    poses = {kf0.id: kf0.T_wc.copy(), kfj.id: kf0.T_wc @ T_rel}
    # Points seen by the pair: triangulated from it.
    xyz: dict[int, np.ndarray] = {}
    _triangulate_points(m, K, kf0.id, kfj.id, poses, xyz, tc)
    if len(xyz) < cfg.min_common // 2:
        return RestructureReport(False, f"{len(xyz)} points from the pair", (kf0.id, kfj.id), par)
    # Every other keyframe by PnP on those points, started from its current pose scaled to the new gauge.
    for kf in kfs:
        if kf.id in poses:
            continue
        seen = [(pid, _seen(m.points[pid], kf)) for pid in sorted(xyz)]
        seen = [(pid, uv) for pid, uv in seen if uv is not None]
        if len(seen) < tc.min_inliers:
            return RestructureReport(False, f"keyframe {kf.id} sees {len(seen)} re-triangulated points", (kf0.id, kfj.id), par)
        Xw = np.stack([xyz[pid] for pid, _ in seen])
        uv = np.stack([uv for _, uv in seen])
        est = estimate_pose(K, Xw, uv, kf.T_wc, tc, seed)
        if not est.ok:
            return RestructureReport(False, f"keyframe {kf.id}: {est.reason}", (kf0.id, kfj.id), par)
        poses[kf.id] = est.T_wc
    # The remaining points from the widest pair of keyframes that saw them.
    for pid, p in m.points.items():
        if pid not in xyz:
            X = _widest_pair_point(K, p.obs, poses, tc)
            if X is not None:
                xyz[pid] = X
    for kf in kfs:
        kf.T_wc = poses[kf.id]
    for pid in [pid for pid in m.points if pid not in xyz]:
        tid = m.points.pop(pid).track_id
        if track_to_point.get(tid) == pid:
            del track_to_point[tid]
    for pid, X in xyz.items():
        m.points[pid].xyz = X
    return _finish(m, K, cfg, (kf0.id, kfj.id), par)


def _finish(m: SlamMap, K: np.ndarray, cfg: RestructureConfig, pair: tuple[int, int], par: float) -> RestructureReport:
    if cfg.ba_iterations > 0:
        local_bundle_adjustment(m, K, len(m.keyframes), cfg.ba_iterations, cfg.ba_huber_px, n_fixed=1, scale_anchor=cfg.scale_anchor,
                                velocity_sigma_ratio=cfg.velocity_prior, rotation_rate_sigma_rad_s=np.radians(cfg.rotation_rate_prior_deg_s))
    # The per-MCI poses the motion model extrapolates from follow their keyframes (the final re-solve of
    # pose_refit only shapes the output, never tracking).
    m.traj_T = [t.copy() for t in m.trajectory(refit=False).matrices()] if m.traj_t else m.traj_T
    m.restructured += 1
    return RestructureReport(True, "", pair, par, len(m.points))


def _triangulate_points(m: SlamMap, K, a: int, b: int, poses: dict, out: dict, tc: TrackingConfig) -> None:
    ka, kb = m.keyframe(a), m.keyframe(b)
    pids = [pid for pid, p in sorted(m.points.items()) if _seen(p, ka) is not None and _seen(p, kb) is not None]
    if not pids:
        return
    uv1 = np.array([_seen(m.points[pid], ka) for pid in pids])
    uv2 = np.array([_seen(m.points[pid], kb) for pid in pids])
    X = triangulate(K, invert_pose(poses[a]), invert_pose(poses[b]), uv1, uv2)
    good = good_triangulation(K, poses[a], poses[b], uv1, uv2, X, 2.0 * tc.reprojection_threshold_px, tc.min_triangulation_deg)
    for k in np.flatnonzero(good):
        out[pids[k]] = X[k].copy()


def _widest_pair_point(K, obs: dict, poses: dict, tc: TrackingConfig) -> np.ndarray | None:
    """A point triangulated from the two of its observing keyframes farthest apart, if it passes the usual checks."""
    kids = sorted(k for k in obs if k in poses)
    best = None
    for i, a in enumerate(kids):
        for b in kids[i + 1:]:
            d = float(np.linalg.norm(poses[a][:3, 3] - poses[b][:3, 3]))
            if best is None or d > best[0]:
                best = (d, a, b)
    if best is None:
        return None
    _, a, b = best
    uv1, uv2 = np.asarray(obs[a])[None], np.asarray(obs[b])[None]
    X = triangulate(K, invert_pose(poses[a]), invert_pose(poses[b]), uv1, uv2)
    ok = good_triangulation(K, poses[a], poses[b], uv1, uv2, X, 2.0 * tc.reprojection_threshold_px, tc.min_triangulation_deg)
    return X[0].copy() if ok[0] else None


def maybe_restructure(m: SlamMap, K: np.ndarray, cfg: RestructureConfig, icfg: InitializationConfig, tc: TrackingConfig,
                      track_to_point: dict[int, int], seed: int = 0) -> RestructureReport | None:
    """Re-initialise ``m`` when :func:`restructure_due` says so; None when it is not due."""
    j = restructure_due(m, K, cfg)
    return None if j is None else restructure_map(m, K, j, cfg, icfg, tc, track_to_point, seed)
