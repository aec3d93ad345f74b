"""Checks and corrections of one MCI-to-MCI KLT step: a track's step against the homography of the others
(:func:`step_consistent`), the shift a constant-velocity warp leaves where the image motion accelerates
(:func:`remove_curvature_shift`), and patch correlation between the two ends of a step (:func:`patch_ncc`).

Detection and KLT itself are in :mod:`evpose.slam.features`, whose docstring records the measurements behind these
(sessions 12-27: the curvature shift, the first-step residual, NCC as a track-quality signal).
"""

from __future__ import annotations

import cv2
import numpy as np

def step_consistent(p0: np.ndarray, p1: np.ndarray, ok: np.ndarray, judge: np.ndarray, max_residual_px: float,
                    min_tracks: int = 12) -> np.ndarray:
    """False for the ``judge`` steps ``p0`` -> ``p1`` farther than ``max_residual_px`` from a RANSAC homography of the
    other ``ok`` steps (of all ``ok`` steps when fewer than ``min_tracks`` are left); True elsewhere.

    Nothing is judged when fewer than ``min_tracks`` steps are ``ok`` or no homography is found. OpenCV's RANSAC
    seeds its own generator on every call, so the mask is deterministic.
    """
    keep = np.ones(len(p0), bool)
    fit = np.flatnonzero(ok & ~judge)
    if len(fit) < min_tracks:
        fit = np.flatnonzero(ok)
    idx = np.flatnonzero(ok & judge)
    if len(fit) < min_tracks or not len(idx):
        return keep
    H, _ = cv2.findHomography(np.ascontiguousarray(p0[fit], np.float64), np.ascontiguousarray(p1[fit], np.float64), cv2.RANSAC,
                              float(max_residual_px))
    if H is None:
        return keep
    pred = cv2.perspectiveTransform(np.ascontiguousarray(p0[idx], np.float64).reshape(-1, 1, 2), H).reshape(-1, 2)
    keep[idx] = np.linalg.norm(p1[idx] - pred, axis=1) <= max_residual_px
    return keep



def remove_curvature_shift(p0: np.ndarray, p1: np.ndarray, ok: np.ndarray, ids: np.ndarray, motion: dict, dt_s: float,
                           dt_prev_s: float, span_s: float, gain: float, perpendicular: bool,
                           max_shift_px: float = 0.0) -> tuple[np.ndarray, dict]:
    """Tracks ``p0`` -> ``p1`` (one MCI-to-MCI step of ``dt_s``) less the change of the shift a constant-velocity warp
    leaves where the image motion accelerates; returns (corrected ``p1``, the new ``motion`` of the ``ok`` tracks).

    An MCI warps its events, spread over ``span_s``, to the window's middle with one velocity: under a constant image
    acceleration ``a`` an event ``t`` off the middle lands ``a t^2 / 2`` off, so the corner shows ``a span^2 / 24`` (the
    mean) towards the acceleration, the inside of a turn. ``a`` is each track's own, from its last two steps (``motion``:
    track id -> (velocity of its last step px/s, the shift removed from it px), that step ``dt_prev_s`` long); only the
    change of the shift since the previous MCI is removed, so a track keeps the shift it was born with. ``gain``
    scales the model; ``perpendicular`` keeps only the part across the track's motion; ``max_shift_px`` > 0 clips
    each shift's length (a KLT jump or a step across a blank gap makes a huge acceleration).
    """
    out = p1.copy()
    idx = np.flatnonzero(ok)
    tids = ids[idx].tolist()
    v = (p1[idx].astype(np.float64) - p0[idx]) / max(dt_s, 1e-6)
    s = np.zeros_like(v)
    has = np.array([t in motion for t in tids], bool)
    if dt_prev_s > 0 and has.any():
        h = np.flatnonzero(has)
        v0 = np.array([motion[tids[k]][0] for k in h]).reshape(-1, 2)
        s0 = np.array([motion[tids[k]][1] for k in h]).reshape(-1, 2)
        acc = (v[h] - v0) / (0.5 * (dt_s + dt_prev_s))
        sh = gain * acc * span_s ** 2 / 24.0
        if perpendicular:
            u = v[h] / np.maximum(np.hypot(v[h, 0], v[h, 1]), 1e-9)[:, None]
            sh = sh - u * (sh * u).sum(axis=1)[:, None]
        if max_shift_px > 0:
            n = np.hypot(sh[:, 0], sh[:, 1])
            sh = np.where((n > max_shift_px)[:, None], sh * (max_shift_px / np.maximum(n, 1e-12))[:, None], sh)
        s[h] = sh
        out[idx[h]] = p1[idx[h]] - (sh - s0)
    return out, {t: (v[k], s[k]) for k, t in enumerate(tids)}



def patch_ncc(img0: np.ndarray, img1: np.ndarray, uv0: np.ndarray, uv1: np.ndarray, radius: int = 5) -> np.ndarray:
    """Normalised cross-correlation of the (2 radius + 1)^2 patches around ``uv0`` in ``img0`` and ``uv1`` in ``img1``
    (nearest pixel; -1 where a patch leaves the image or is flat), float64 (N,)."""
    n = len(uv0)
    out = np.full(n, -1.0)
    if n == 0:
        return out
    h, w = img0.shape
    c0 = np.rint(uv0).astype(np.int64)
    c1 = np.rint(uv1).astype(np.int64)
    inside = np.all((c0 >= radius) & (c1 >= radius), axis=1)
    inside &= (c0[:, 0] < w - radius) & (c1[:, 0] < w - radius) & (c0[:, 1] < h - radius) & (c1[:, 1] < h - radius)
    k = np.flatnonzero(inside)
    if not len(k):
        return out
    d = np.arange(-radius, radius + 1)
    dy, dx = np.meshgrid(d, d, indexing="ij")
    a = img0[c0[k, 1, None, None] + dy, c0[k, 0, None, None] + dx].reshape(len(k), -1).astype(np.float64)
    b = img1[c1[k, 1, None, None] + dy, c1[k, 0, None, None] + dx].reshape(len(k), -1).astype(np.float64)
    a -= a.mean(axis=1, keepdims=True)
    b -= b.mean(axis=1, keepdims=True)
    den = np.sqrt((a * a).sum(axis=1) * (b * b).sum(axis=1))
    ncc = np.where(den > 0, (a * b).sum(axis=1) / np.where(den > 0, den, 1.0), -1.0)
    out[k] = ncc
    return out
