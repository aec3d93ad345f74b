"""Re-finding map points by KLT from the keyframe MCIs that observed them (the local-map matcher of event SLAM).

A KLT track that dies between two MCIs takes its map point with it: on the
simulated landing only about two thirds of the tracks survive each MCI, points
collect two or three keyframe observations and each pose rests on about 30 of
130 tracks. Here an untracked local-map point is tracked again by pyramidal KLT
from a keyframe observation (in that keyframe's MCI) into the current MCI,
started at its projection by the estimated pose; the match must pass KLT's
forward-backward check and land near the projection. The backward pass starts
from the observation shifted by the forward result's offset from the
projection: keyframe and MCI are tens of pixels apart, and a backward pass
started at the forward result converged for about 2 % of the candidates (16 %
with the guided start, landing seed 0). An edge makes events only when it moves
across itself, so a point missing in the newest keyframe's view is tried from
older ones. Session 12, landing seed 2: of 5764 KLT candidates 14 % passed the
forward-backward check and 2.7 % landed within the 3 px radius (median distance of the passing ones 5.6 px); about 110 map points project into each MCI,
77 of them seen in the local window, and 39 are tracked. Warping each keyframe MCI into the current view first (by
the homography of the plane fitted to its points) left that unchanged (13 %, 2.6 %), so rotation and scale change
between the views are not what stops KLT there.

Re-anchoring the tracked points as well (session 20, ``/tmp/s20/post9/``, removed; the patch is
``/tmp/s20/post9/reanchor.patch``): MCI-to-MCI KLT adds its error at every step (landing seed 10, tracks against the
truth: median 0.9 px one or two MCIs after birth, 1.2-1.4 px at 2-16, 2.1 px at 16-32, 3.4 px at 32-64), so each
tracked map point was re-measured by :func:`klt_near` from its oldest observation in a kept keyframe MCI, started at
the track's position, and moved when the result passed within a radius of it. Landing event-only, all 72 seeds
(defaults 2.40 %, 46 within 2 %; seeds 0-23 / 24-47 / 48-71 1.82 / 2.86 / 2.51 %): at keyframes only, 2 px -> 2.42 %
(46), paired +0.03 +- 0.24 points (38 better, 34 worse; 2.25 / 2.13 / 2.89 %); at every MCI, 2 px -> 2.66 % (48,
median 1.75 -> 1.63), +0.27 +- 0.24, with new losses of the map in the turn (seeds 4, 6, 8: under 12 tracked map
points at 2.06-2.4 s); every MCI, 1 px -> 2.60 % (47), +0.21 +- 0.23 (36 / 36; 2.69 / 2.54 / 2.57 %). The last
mended every run of the defaults that runs away after the turn (seeds 10, 24, 31, 32, 37, 38, 55, 63, 65: 2.75-4.65
-> 1.06-1.88 %) and sent as many others away (1, 4, 9, 17, 21, 28, 44, 56, 58, 61: 1.16-2.38 -> 3.18-11.34 %): the
outcome after the turn is reshuffled, not stabilised; nor were the tracks more precise (1 px, every MCI; seeds 10 /
2, median error 4-8 MCIs after birth 1.16 / 1.23 -> 1.29 / 1.20 px, 16-32 MCIs 2.06 / 1.82 -> 2.24 / 1.86 px): the
error that grows with a track's age is not KLT's step-by-step drift
(:attr:`evpose.slam.tracking_config.TrackingConfig.ba_window`). Main-thread CPU per MCI (median of the runs' medians,
unpaired) 22.3 -> 23.5 / 27.6 / 28.3 ms.
"""

from __future__ import annotations

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.config import FeatureConfig
import cv2

from evpose.slam.features import KLT_NO_ERROR
from evpose.slam.geometry import project


def klt_refind_points(m: SlamMap, img8: np.ndarray, K: np.ndarray, T_wc: np.ndarray, tracked_pids: set[int], occupied_uv: np.ndarray,
                      window: int, radius: float, fcfg: FeatureConfig, border: int = 8,
                      max_keyframes: int = 1) -> tuple[list[int], np.ndarray]:
    """Untracked points of the last ``window`` keyframes found in ``img8`` by KLT from keyframe MCIs: (point ids, pixels (M, 2)).

    A match lies within ``radius`` px of the projection by ``T_wc``; matches within 2 px of ``occupied_uv`` (tracked
    points) or of another match are dropped as conflicts.
    """
    kfs = [kf for kf in m.keyframes[-window:] if kf.image8 is not None]
    if not kfs:
        return [], np.zeros((0, 2))
    first = m.keyframes[-window:][0].id
    cand = [pid for pid, p in sorted(m.points.items()) if pid not in tracked_pids and p.obs and max(p.obs) >= first]
    if not cand:
        return [], np.zeros((0, 2))
    h, w = img8.shape
    proj, z = project(K, invert_pose(T_wc), np.stack([m.points[p].xyz for p in cand]))
    inside = (z > 0) & (proj[:, 0] >= border) & (proj[:, 0] < w - border) & (proj[:, 1] >= border) & (proj[:, 1] < h - border)
    todo = set(np.flatnonzero(inside).tolist())
    pids_out, uv_out = [], []
    # Newest keyframe first; a point missed there is tried from older views, whose event image may look more like this one.
    for kf in reversed(kfs[-max_keyframes:] if max_keyframes > 0 else kfs):
        idx = np.array([i for i in sorted(todo) if kf.id in m.points[cand[i]].obs], np.int64)
        if not len(idx):
            continue
        src = np.array([m.points[cand[i]].obs[kf.id] for i in idx], np.float32)
        found, ok = klt_near(kf.image8, img8, src, proj[idx], radius, fcfg)
        for k in np.flatnonzero(ok):
            pids_out.append(cand[idx[k]])
            uv_out.append(found[k].astype(np.float64))
            todo.discard(int(idx[k]))
    if not pids_out:
        return [], np.zeros((0, 2))
    uv = np.array(uv_out)
    keep = np.ones(len(uv), bool)
    if len(uv) > 1:
        d = np.linalg.norm(uv[:, None] - uv[None], axis=2) + np.eye(len(uv)) * 1e9
        keep &= d.min(axis=1) >= 2.0
    if len(occupied_uv):
        keep &= np.linalg.norm(uv[:, None] - np.asarray(occupied_uv, np.float64)[None], axis=2).min(axis=1) >= 2.0
    order = np.argsort(np.array(pids_out)[keep], kind="stable")
    return [pids_out[i] for i in np.flatnonzero(keep)[order]], uv[keep][order]


def klt_near(src8: np.ndarray, img8: np.ndarray, src: np.ndarray, guess: np.ndarray, radius: float,
             fcfg: FeatureConfig) -> tuple[np.ndarray, np.ndarray]:
    """:func:`track_features` with ``guess_back`` from ``src8`` into ``img8``, started at ``guess``, whose forward results
    must also land within ``radius`` px of ``guess``: (positions (N, 2) float32, ok mask (N,)).

    The same result as :func:`track_features` followed by the radius test, bit for bit (KLT tracks each point on its
    own), but the backward pass runs only for the forward results that passed: about 3 % of the candidates land within
    the radius, and the backward pass of the rest was half the search's KLT time. Session 19 (``/tmp/s19/turn9/cpu.py``,
    landing event-only seeds 0-3 twice, the two versions alternated in one process): main-thread CPU per MCI median
    27.75 -> 23.72 ms (mean 33.69 -> 29.89 ms), same trajectories.
    """
    n = len(src)
    if n == 0:
        return np.zeros((0, 2), np.float32), np.zeros(0, bool)
    p0 = np.ascontiguousarray(src, np.float32).reshape(-1, 1, 2)
    p1_init = np.ascontiguousarray(guess, np.float32).reshape(-1, 1, 2).copy()
    win = (int(fcfg.klt_window_px), int(fcfg.klt_window_px))
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01)
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(src8, img8, p0, p1_init, winSize=win, maxLevel=int(fcfg.klt_levels), criteria=crit,
                                          flags=cv2.OPTFLOW_USE_INITIAL_FLOW | KLT_NO_ERROR)
    found = p1.reshape(-1, 2)
    h, w = img8.shape
    ok = (st1.ravel() == 1) & (found[:, 0] >= 0) & (found[:, 0] <= w - 1) & (found[:, 1] >= 0) & (found[:, 1] <= h - 1)
    ok &= np.linalg.norm(found.astype(np.float64) - np.asarray(guess, np.float64), axis=1) <= radius
    idx = np.flatnonzero(ok)
    if len(idx):
        p0_init = (p0[idx] + (p1[idx] - p1_init[idx])).astype(np.float32)
        p0b, st2, _ = cv2.calcOpticalFlowPyrLK(img8, src8, np.ascontiguousarray(p1[idx]), p0_init, winSize=win,
                                               maxLevel=int(fcfg.klt_levels), criteria=crit,
                                               flags=cv2.OPTFLOW_USE_INITIAL_FLOW | KLT_NO_ERROR)
        fb = np.linalg.norm(p0b.reshape(-1, 2) - p0[idx].reshape(-1, 2), axis=1)
        ok[idx] = (st2.ravel() == 1) & (fb <= fcfg.klt_max_bidir_error_px)
    return found.astype(np.float32), ok


def keep_keyframe_image(m: SlamMap, kf, img8: np.ndarray, window: int) -> None:
    """Keep ``kf``'s MCI as a KLT source; keyframes out of the local window drop theirs (never searched, only snapshot weight)."""
    kf.image8 = img8
    for old in m.keyframes[:-window]:
        old.image8 = None
