"""Baseline test of two-view initialisation that needs no decomposition: the parallax left after the best pure rotation.

A homography or essential matrix decomposed from tracks with almost no baseline
(a camera turning fast at a few millimetres of translation per MCI) still
"triangulates" points in front of both views, and its decomposed translation
is arbitrary, so the triangulation angle it reports says nothing. The rotation
that best maps the first view's bearings onto the second's (orthogonal
Procrustes) explains all the flow of a pure rotation; what it leaves is the
flow only translation makes, and its median angle bounds the real parallax.
"""

from __future__ import annotations

import numpy as np


def bearings(K: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Unit viewing rays (N, 3) of ideal-pinhole pixels ``uv`` (N, 2)."""
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    b = np.c_[(uv[:, 0] - K[0, 2]) / K[0, 0], (uv[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(uv))]
    return b / np.linalg.norm(b, axis=1, keepdims=True)


def best_rotation(b1: np.ndarray, b2: np.ndarray) -> np.ndarray:
    """Rotation ``R`` minimising ``sum |b2 - R b1|^2`` over unit rays (Kabsch), (3, 3)."""
    U, _, Vt = np.linalg.svd(b2.T @ b1)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    return U @ D @ Vt


def rotation_compensated_parallax_deg(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, trim: float = 0.8) -> float:
    """Median angle between the second view's rays and the first view's rays rotated by the best pure rotation, degrees.

    The rotation is fitted twice, the second time to the ``trim`` share of matches it explained best (a few bad tracks
    must not tilt it). NaN with fewer than three matches.
    """
    b1, b2 = bearings(K, p1), bearings(K, p2)
    if len(b1) < 3:
        return float("nan")
    R = best_rotation(b1, b2)
    res = _angles(b2, b1 @ R.T)
    keep = res <= np.quantile(res, trim)
    if keep.sum() >= 3:
        R = best_rotation(b1[keep], b2[keep])
        res = _angles(b2, b1 @ R.T)
    return float(np.degrees(np.median(res)))


def _angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # atan2 of cross and dot: accurate for the sub-degree angles this test is about (arccos is not).
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.sum(a * b, axis=1))


def rotation_fit_disagreement_deg(K: np.ndarray, p1: np.ndarray, p2: np.ndarray, T_wc2: np.ndarray) -> float:
    """Angle between the rotation of a two-view solution (``T_wc2``, first view at the origin) and the pure rotation
    fitted to the rays, degrees. Over a short baseline the fit is close to the true rotation (translation adds flow of
    the order of the parallax); a decomposition that turns the camera by degrees more than the rays do is wrong."""
    R_fit = best_rotation(bearings(K, p1), bearings(K, p2))
    R_21 = np.asarray(T_wc2)[:3, :3].T
    c = (np.trace(R_fit.T @ R_21) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
