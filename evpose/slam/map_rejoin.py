"""Re-joining a lost, not yet IMU-initialised event-inertial map: the next two-view map is placed in its frame.

Indoors (simulated room, E-I-C2) the visual tracking fails every few hundred
milliseconds; a map the IMU initialisation has not reached coasts for
``InertialConfig.coast_s`` and is then lost, and the next two-view
initialisation opened a new map with its own frame and scale (seed 2: five
maps, none ever long enough for the IMU initialisation). Here that new map is
expressed in the lost map's frame instead and appended to it: its first
keyframe at the pose the lost map coasts to at that time (gyro rotation,
camera-frame velocity held constant), its scale set so that the baseline of
its two initial keyframes is the distance the coasting covers between them.
The combined map keeps growing, so the IMU initialisation can reach it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.coasting import coast_pose


@dataclass
class RejoinCandidate:
    """A map lost while coasting, with what its coasting needs."""

    map: SlamMap
    v_cam: np.ndarray
    """Camera-frame velocity of the map when it was lost, map units per us."""


def scene_depth(m: SlamMap, kf, min_points: int) -> float | None:
    """Median depth (camera z, map units) of the points of ``m`` that keyframe ``kf`` observes; None under ``min_points``."""
    Tcw = np.linalg.inv(kf.T_wc)
    z = [float(Tcw[2, :3] @ p.xyz + Tcw[2, 3]) for p in m.points.values() if kf.id in p.obs]
    z = [v for v in z if v > 0]
    return float(np.median(z)) if len(z) >= max(min_points, 1) else None


def depth_scale(old: SlamMap, new: SlamMap, min_points: int) -> float | None:
    """Scale taking ``new``'s units to ``old``'s so that the scene depth agrees across the gap: the median point depth of
    ``old``'s newest keyframe that observes at least ``min_points`` of its points, over that of ``new``'s first keyframe
    (``InertialConfig.rejoin_scale_depth_weight``); None when either has too few points."""
    d_new = scene_depth(new, new.keyframes[0], min_points)
    if d_new is None:
        return None
    for kf in reversed(old.keyframes):
        d_old = scene_depth(old, kf, min_points)
        if d_old is not None:
            return d_old / d_new
    return None


def rejoin_similarity(old: SlamMap, new: SlamMap, R0_wc: np.ndarray, R1_wc: np.ndarray, v_cam: np.ndarray,
                      depth_weight: float = 0.0, depth_min_points: int = 8) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(R, t, s)`` taking the two-keyframe map ``new`` (first keyframe at the origin) into ``old``'s frame, ``x -> s R x + t``.

    ``R0_wc``/``R1_wc``: the old map's camera orientation at the two keyframes' times (from the gyro). None when the
    coasting covers no distance or the new map has no baseline. ``depth_weight`` > 0: the scale is the weighted
    geometric mean of the baseline's (the two-view baseline against the coasted distance) and the scene depth's
    (:func:`depth_scale`, keyframes seeing at least ``depth_min_points`` points; the baseline's alone where they do not),
    ``s_baseline^(1 - w) s_depth^w``.
    """
    kf0, kf1 = new.keyframes[0], new.keyframes[1]
    T0 = coast_pose(old, kf0.t_us, R0_wc, v_cam)
    T1 = coast_pose(old, kf1.t_us, R1_wc, v_cam)
    baseline_old = float(np.linalg.norm(T1[:3, 3] - T0[:3, 3]))
    baseline_new = float(np.linalg.norm(kf1.T_wc[:3, 3] - kf0.T_wc[:3, 3]))
    if not (baseline_old > 0 and baseline_new > 0 and np.isfinite(baseline_old / baseline_new)):
        return None
    # The new frame is that of its first keyframe (identity pose): its orientation becomes the coasted one.
    R = T0[:3, :3] @ kf0.T_wc[:3, :3].T
    s = baseline_old / baseline_new
    if depth_weight > 0:
        s_depth = depth_scale(old, new, depth_min_points)
        if s_depth is not None and s_depth > 0:
            s = s_depth if depth_weight >= 1 else float(np.exp((1.0 - depth_weight) * np.log(s) + depth_weight * np.log(s_depth)))
    t = T0[:3, 3] - s * (R @ kf0.T_wc[:3, 3])
    return R, t, s


def merge_into(old: SlamMap, new: SlamMap, R: np.ndarray, t: np.ndarray, s: float) -> int:
    """Append ``new`` (keyframes, points, trajectory) to ``old`` through ``x -> s R x + t``; returns the first appended keyframe id.

    Keyframe ids of ``new`` are shifted past ``old``'s (ids grow along a map); point ids are global already.
    """

    def tf(T: np.ndarray) -> np.ndarray:
        out = T.copy()
        out[:3, :3] = R @ T[:3, :3]
        out[:3, 3] = s * (R @ T[:3, 3]) + t
        return out

    off = old.keyframes[-1].id + 1 if old.keyframes else 0
    for kf in new.keyframes:
        kf.id += off
        kf.T_wc = tf(kf.T_wc)
        old.keyframes.append(kf)
    for pid, p in new.points.items():
        p.xyz = s * (R @ p.xyz) + t
        p.obs = {k + off: uv for k, uv in p.obs.items()}
        p.created_kf += off
        old.points[pid] = p
    for tt, T, ref, rel in zip(new.traj_t, new.traj_T, new.traj_ref, new.traj_rel):
        if old.traj_t and tt <= old.traj_t[-1]:
            continue
        rel = rel.copy()
        rel[:3, 3] *= s
        old.traj_t.append(int(tt))
        old.traj_T.append(tf(T))
        old.traj_ref.append(ref + off if ref >= 0 else -1)
        old.traj_rel.append(rel)
    old.lost_reason = ""
    old.segment_start_kf = off
    return off
