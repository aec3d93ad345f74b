"""Re-solving the PnP-placed per-MCI poses of a refined trajectory on the map points' current positions.

An MCI's pose is solved once, online, on the points as they were then: a keyframe or two old, triangulated over short
baselines. The local bundle adjustments of the next keyframes move those points (and the keyframes), and a refined
trajectory (:meth:`evpose.slam.atlas.SlamMap.trajectory`) carries the MCI along with its reference keyframe only, as
a rigid body: the pose keeps the error of the points it was solved on. With each pose's PnP inliers (point ids,
pixels) and its MCI's other tracks recorded (:attr:`SlamMap.traj_obs`), the pose is re-solved on the same pixels with
the points where the map holds them at the end, joined by the tracks that got a point later: a motion-only refinement
per MCI, points fixed (unlike the full BA at the end, :mod:`evpose.slam.map_restructure`, which moved the keyframes and
made every indoor map worse). Figures: :attr:`evpose.slam.tracking_config.TrackingConfig.refit_tracked_poses`.

Where the indoor ATE sits in tracked stretches (session 29, ``/tmp/s29/jit29``; ``capture.py`` records each run's maps,
per-MCI poses and every PnP pose's inliers; ``ana.py`` .. ``ana4.py``, ``corr.py``; indoor event-only seeds 0-7 at the
session-28 defaults, 3.90 %). After each map's Sim(3) alignment the PnP-placed poses hold 84 % of the squared position
residual (329 poses, RMS 100 mm), the coasted ones 9 % (1061 poses, 19 mm) and the maps' first (two-view reference)
poses 6 % (42 poses, 76 mm). The maps tracking the two legs (0-0.83 s and 2.4-2.97 s, 16-43 poses each; the turn
between them is coasted in three maps) give about two thirds of the summed ATE, seed 4's last map alone 7.7 of its
10.3 points. That error is slow, not pose-to-pose: the residual minus its +-4-pose moving average is 40 mm RMS of the
100, and replacing the tracked poses by that average makes the ATE worse (4.15 %); the map's scale wanders along a leg
(Sim(3) scale over 7-pose windows 0.7-2.1 times the map's own on seed 0's first map, 0.2-14 on seed 4's last map, whose
first 0.3 s track 15-26 points from 1200-1800-event MCIs; its online poses jump 100-300 mm between MCIs there).
Aligning each leg's map in halves would give 2.78 instead of 3.96 % (distance-weighted). Per pose (``corr.py``, 271 PnP
poses of ``reprojection_threshold_px`` 2.4, Spearman against the residual / its fast part, both over the map's
distance): points used -0.08 / +0.32, PnP RMS +0.04 / +0.13, median point age in keyframes +0.09 / +0.04, keyframe
observations per point +0.09 / +0.07, MCI events +0.27 / -0.02: no per-MCI figure flags the bad poses. Composing the
poses otherwise does not help (``comp.py``): the online poses 3.78 %, the keyframe correction interpolated between the
reference keyframe and the next 3.90 %, the next keyframe's 4.04 %, the reference keyframe's (default) 3.90 %.
With this re-solve (``split.py``, run ``chk``: the defaults, 3.73 %) the PnP-placed poses still hold 83 % of the
squared residual at 96 mm RMS (fast part 37 mm): it takes off a little of both, and the legs' slow scale wander stays.
That wander is the keyframe steps', not the points' (session 29, :mod:`evpose.slam.local_map`): the map's depth scale
holds within 10 % along a leg while the steps' length runs 0.2-12 times the true one, each step's translation error
following its rotation error (the rotation-translation valley of a narrow view).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.geometry import project
from evpose.slam.pnp_motion_prior import refine_pose_with_pose_prior

MIN_POINTS = 6
"""A pose is re-solved only on at least this many of its inliers still in the map (six pairs fix a pose with margin)."""


def refit_pose(K: np.ndarray, Xw: np.ndarray, uv: np.ndarray, T_wc: np.ndarray) -> np.ndarray:
    """Levenberg-Marquardt refinement of the pose ``T_wc`` (``T_world_cam``) on the 2-D / 3-D pairs ``uv`` / ``Xw``."""
    T_cw = invert_pose(T_wc)
    rvec, _ = cv2.Rodrigues(T_cw[:3, :3])
    tvec = T_cw[:3, 3].reshape(3, 1).copy()
    obj = np.ascontiguousarray(Xw, np.float64).reshape(-1, 1, 3)
    img = np.ascontiguousarray(uv, np.float64).reshape(-1, 1, 2)
    try:
        rvec, tvec = cv2.solvePnPRefineLM(obj, img, K, None, rvec, tvec)
    except cv2.error:
        return T_wc  # a degenerate set (e.g. points along one ray): keep the pose as it was
    R, _ = cv2.Rodrigues(rvec)
    out = np.eye(4)
    out[:3, :3] = R
    out[:3, 3] = tvec.ravel()
    out = invert_pose(out)
    return out if np.all(np.isfinite(out)) else T_wc


@dataclass
class PoseObservations:
    """What placed one MCI pose: its PnP inliers' point ids (M,) and pixels (M, 2), and the MCI's other tracks' ids (N,)
    and pixels (N, 2) (tracks without a map point then, or PnP outliers)."""

    point_ids: np.ndarray
    uv: np.ndarray
    track_ids: np.ndarray
    track_uv: np.ndarray
    prior_sigmas: tuple[float, float] | None = None
    """(rotation rad, translation map units) of the motion prior the pose was refined with online
    (:mod:`evpose.slam.pnp_motion_prior`); the re-solve keeps it around the pose it starts from. None: no prior."""


def refit_trajectory(K: np.ndarray, t_us: list[int], T_wc: list[np.ndarray], obs: dict[int, PoseObservations], points: dict,
                     threshold_px: float, min_points: int = MIN_POINTS) -> list[np.ndarray]:
    """``T_wc`` (poses at ``t_us``) with every pose that has recorded observations in ``obs`` (by time) re-solved on
    the points (``points``: id -> :class:`MapPoint`) where they are now: first from itself on those of its inliers still
    in the map (when at least ``min_points`` are), then once more with the MCI's other tracks whose track now carries a
    point (triangulated later, or re-found) and reprojects within ``threshold_px`` of it; the other poses unchanged."""
    by_track = {p.track_id: pid for pid, p in points.items()}
    out = list(T_wc)
    for i, t in enumerate(t_us):
        o = obs.get(int(t))
        if o is None:
            continue
        keep = np.array([p in points for p in o.point_ids.tolist()], bool)
        if keep.sum() < min_points:
            continue
        Xw = np.stack([points[int(p)].xyz for p in o.point_ids[keep]])
        uv = o.uv[keep].astype(np.float64)
        if o.prior_sigmas is None:
            solve = refit_pose
        else:
            # The online pose carried the motion prior; re-solving without it would hand the pose back to the valley
            # the prior held it out of, so the prior stays, centred on the pose as the keyframes carry it now.
            T_prior_cw = invert_pose(out[i])

            def solve(K_, X_, u_, T_wc_):
                return invert_pose(refine_pose_with_pose_prior(K_, X_, u_, invert_pose(T_wc_), T_prior_cw, *o.prior_sigmas))
        T = solve(K, Xw, uv, out[i])
        have = set(o.point_ids[keep].tolist())
        extra = [(by_track[tid], k) for k, tid in enumerate(o.track_ids.tolist()) if tid in by_track and by_track[tid] not in have]
        if extra:
            Xe = np.stack([points[pid].xyz for pid, _ in extra])
            ue = o.track_uv[[k for _, k in extra]].astype(np.float64)
            proj, z = project(K, invert_pose(T), Xe)
            near = (z > 0) & (np.linalg.norm(proj - ue, axis=1) < threshold_px)
            if near.any():
                T = solve(K, np.r_[Xw, Xe[near]], np.r_[uv, ue[near]], T)
        out[i] = T
    return out


def keyframe_interpolated(t_us: list[int], T_wc: list[np.ndarray], placed: set[int], kf_t_us: list[int],
                          kf_T_wc: list[np.ndarray]) -> list[np.ndarray]:
    """``T_wc`` (poses at ``t_us``) with every pose whose time is in ``placed`` (the PnP-placed MCIs) and lies strictly
    between two keyframe times replaced by the poses at those two keyframes interpolated at its time (position linear,
    rotation along the geodesic); keyframe MCIs, poses outside the keyframes' span and the other poses unchanged. The
    pose at a keyframe is ``T_wc``'s at the keyframe's time when it has one (a keyframe MCI's own pose, re-solved on
    the final points), else the keyframe's ``kf_T_wc``: offline, session 34, anchoring on the re-solved keyframe MCIs
    instead of the bundle-adjusted keyframes took another -0.013 +- 0.007 / -0.009 +- 0.003 / -0.010 +- 0.003 points
    off indoor 0-19 / 20-39 / landing 0-23 (``/tmp/s34/drift34/kfa.py``).

    Why: the keyframes are placed by the local BAs on every point they see, an MCI between them by one PnP on its own
    tracks, and between two keyframes 20-60 ms apart the motion is smoother than that PnP's noise. Session 34
    (:attr:`evpose.slam.tracking_config.TrackingConfig.refit_keyframe_interpolation` has the figures)."""
    if len(kf_t_us) < 2 or not placed:
        return list(T_wc)
    kt = np.asarray(kf_t_us, np.int64)
    if np.any(np.diff(kt) <= 0):
        # Keyframe times rise along a map (none repeated or out of order in session 34's 64 runs); should they not,
        # order them and keep the newest keyframe at a repeated time.
        order = np.argsort(kt, kind="stable")
        kt, kf_T_wc = kt[order], [kf_T_wc[i] for i in order]
        keep = np.r_[kt[1:] != kt[:-1], True]
        kt, kf_T_wc = kt[keep], [T for T, k in zip(kf_T_wc, keep) if k]
        if len(kt) < 2:
            return list(T_wc)
    at = {int(t): i for i, t in enumerate(t_us)}
    anchors = [T_wc[at[int(k)]] if int(k) in at else T for k, T in zip(kt, kf_T_wc)]
    out = list(T_wc)
    for i, t in enumerate(t_us):
        if int(t) not in placed or not kt[0] < t < kt[-1]:
            continue
        j = int(np.searchsorted(kt, t, side="right"))
        if kt[j - 1] == t:
            continue  # a keyframe MCI keeps its own (re-solved) pose
        Ta, Tb = anchors[j - 1], anchors[j]
        f = (t - kt[j - 1]) / (kt[j] - kt[j - 1])
        R_ab = Ta[:3, :3].T @ Tb[:3, :3]
        rv, _ = cv2.Rodrigues(R_ab)
        R_f, _ = cv2.Rodrigues(rv * f)
        T = np.eye(4)
        T[:3, :3] = Ta[:3, :3] @ R_f
        T[:3, 3] = (1.0 - f) * Ta[:3, 3] + f * Tb[:3, 3]
        out[i] = T
    return out


def first_pose_extrapolated(t_us: list[int], T_wc: list[np.ndarray], span_us: int, young_us: int = 0) -> list[np.ndarray]:
    """``T_wc`` (poses at ``t_us``) with the map's young poses, those less than ``young_us`` after its first one (at least
    the first pose itself), replaced by the motion of the poses from the first later one (the anchor) to the first at
    least ``span_us`` after it, held constant back to each young pose's time (position linear, rotation along the
    geodesic). ``young_us`` 0 replaces only the first pose, anchored on the second. With fewer than three poses from the
    anchor on, the first pose alone is replaced; unchanged with fewer than four poses or when the poses from the anchor
    on lie on one line (then, with ``young_us`` > 0, the first pose alone is replaced if the poses from the second on do
    not lie on one line).

    Why: a map's first pose is its two-view reference keyframe, the gauge every later pose hangs from, and after the
    map's Sim(3) it sits a median 1.8 times the map's RMS off; the young map's next poses, together, place it better
    (figures: :attr:`evpose.slam.tracking_config.TrackingConfig.first_pose_extrapolation_s`). The map's other poses of
    its first ~0.15 s are no better: placed over a few millimetres of baseline on points with almost no depth relief
    (sideways motion read as yaw), they jump 5-7 times the true step in the first 20 ms and bend away from the rest of
    the map (session 35; figures: :attr:`evpose.slam.tracking_config.TrackingConfig.young_pose_extrapolation_s`)."""
    if len(t_us) < 4 or span_us <= 0:
        return list(T_wc)
    t = np.asarray(t_us, np.int64)
    i1 = max(int(np.searchsorted(t, t[0] + max(int(young_us), 0))), 1)
    if i1 > len(t) - 3:
        i1 = 1  # too short a map for its young stretch: only its first pose
    if not _spread_off_one_line(T_wc[i1:]):
        if i1 == 1 or not _spread_off_one_line(T_wc[1:]):
            # The later poses lie on one line (a coast holding one velocity): the first pose moved onto it would leave
            # the map exactly straight, which no Sim(3) aligns (session 34: held-out indoor seed 34's 4-pose map was
            # dropped).
            return list(T_wc)
        i1 = 1
    j = min(max(int(np.searchsorted(t, t[i1] + span_us)), i1 + 1), len(t) - 1)
    T1, Tj = T_wc[i1], T_wc[j]
    rv, _ = cv2.Rodrigues(T1[:3, :3].T @ Tj[:3, :3])
    out = list(T_wc)
    for k in range(i1):
        f = (t[i1] - t[k]) / (t[j] - t[i1])  # how far back, in units of the span actually used
        R_back, _ = cv2.Rodrigues(-rv * f)
        T0 = np.eye(4)
        T0[:3, :3] = T1[:3, :3] @ R_back
        T0[:3, 3] = T1[:3, 3] - f * (Tj[:3, 3] - T1[:3, 3])
        out[k] = T0
    return out


def _spread_off_one_line(T_wc: list[np.ndarray]) -> bool:
    """Whether the positions of ``T_wc`` do not all lie on one line."""
    P = np.stack([T[:3, 3] for T in T_wc])
    sv = np.linalg.svd(P - P.mean(0), compute_uv=False)
    return bool(sv[1] > 1e-9 * sv[0])
