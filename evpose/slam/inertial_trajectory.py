"""Keeping an event-inertial map's per-MCI poses at the scale of its keyframes when a BA changes that scale.

A map's trajectory stores each MCI pose relative to its reference keyframe (``SlamMap.traj_rel``), and the refined
trajectory composes it with the keyframe's current pose, so a BA that moves keyframes carries the poses between them
along. A BA can also change the map's scale along the way: before the IMU initialisation the visual local BA of an
event-inertial map holds one keyframe (the window's scale is a gauge freedom, ``TrackingConfig.ba_scale_anchor`` is
event-only), and the full inertial BA after the initialisation reshapes the whole map to the IMU. The rotations
relative to a keyframe follow the gyro (:func:`evpose.slam.gyro_prior.reanchor_rotations`); the translations stayed in
the scale they were tracked in. On the simulated room (E-I-C2, seed 1, ``reprojection_threshold_px`` 2.4) the first
0.1 s of MCIs stood 13-560 times their true step apart while their keyframes kept 0.1-0.2 of it: 18 m of the run's
19.9 m of summed per-step translation error. Here every MCI's translation relative to its keyframe is scaled by how
much the BA stretched the keyframe path around that keyframe.
"""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import SlamMap


def keyframe_positions(m: SlamMap) -> dict[int, np.ndarray]:
    """Keyframe id -> camera position (3,), copied (what :func:`carry_relative_scale` compares a BA's result with)."""
    return {kf.id: kf.T_wc[:3, 3].copy() for kf in m.keyframes}


def carry_relative_scale(m: SlamMap, before: dict[int, np.ndarray], half_window: int = 3) -> int:
    """Scale each MCI's translation relative to its keyframe by the local stretch of the keyframe path since ``before``.

    The stretch of keyframe ``k`` is the path length through the keyframes within ``half_window`` of it now over that
    path length in ``before`` (keyframes absent from ``before`` are skipped). Returns how many poses changed.
    """
    kfs = [kf for kf in m.keyframes if kf.id in before]
    if len(kfs) < 2:
        return 0
    now = np.stack([kf.T_wc[:3, 3] for kf in kfs])
    old = np.stack([before[kf.id] for kf in kfs])
    moved = np.flatnonzero(np.any(now != old, axis=1))
    if not len(moved):
        return 0
    seg_now = np.linalg.norm(np.diff(now, axis=0), axis=1)
    seg_old = np.linalg.norm(np.diff(old, axis=0), axis=1)
    ratio: dict[int, float] = {}
    lo_moved = max(int(moved[0]) - half_window, 0)
    for i in range(lo_moved, len(kfs)):
        a, b = max(i - half_window, 0), min(i + half_window, len(kfs) - 1)
        d_old, d_now = float(seg_old[a:b].sum()), float(seg_now[a:b].sum())
        if d_old > 0 and d_now > 0 and d_now != d_old:
            ratio[kfs[i].id] = d_now / d_old
    if not ratio:
        return 0
    first = min(ratio)
    changed = 0
    # References grow along the trajectory: walk back from its end until the poses refer to older keyframes.
    for i in range(len(m.traj_ref) - 1, -1, -1):
        ref = m.traj_ref[i]
        if 0 <= ref < first:
            break
        r = ratio.get(ref)
        if r is not None:
            m.traj_rel[i][:3, 3] *= r
            changed += 1
    return changed


def path_velocities(keyframes: list, T_cam_imu: np.ndarray, span_s: float) -> dict[int, np.ndarray]:
    """Keyframe id -> world velocity of the IMU from the map's own keyframe path (:attr:`InertialWindowConfig.init_velocity_span_s`).

    The slope of a straight line fitted to the IMU positions (``p_wc + R_wc t_cb``) of the keyframes within
    ``span_s / 2`` either side of each keyframe (centred; one-sided at the map's ends), over the visually tracked
    keyframes (``Keyframe.visual``) when at least three of them are there, else over all of them: a fit over many
    keyframes made a few ms apart, not a difference of two, whose centimetre jumps were metres per second off. Keyframes
    with fewer than two neighbours in time get none. Map units per second.
    """
    if span_s <= 0 or len(keyframes) < 2:
        return {}
    t_cb = np.asarray(T_cam_imu, np.float64)[:3, 3]
    t = np.array([kf.t_us for kf in keyframes], np.float64) / 1e6
    p = np.stack([kf.T_wc[:3, 3] + kf.T_wc[:3, :3] @ t_cb for kf in keyframes])
    vis = np.array([bool(getattr(kf, "visual", True)) for kf in keyframes])
    out = {}
    half = 0.5 * span_s
    for i, kf in enumerate(keyframes):
        sel = np.flatnonzero(np.abs(t - t[i]) <= half)
        if vis[sel].sum() >= 3:
            sel = sel[vis[sel]]
        if len(sel) < 2 or np.ptp(t[sel]) <= 0:
            continue
        dt = t[sel] - t[sel].mean()
        out[kf.id] = (dt @ (p[sel] - p[sel].mean(0))) / (dt @ dt)
    return out
