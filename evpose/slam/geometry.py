"""Small multi-view geometry helpers shared by initialisation, tracking and mapping (pinhole, ideal pixels)."""

from __future__ import annotations

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose


def project(K: np.ndarray, T_cam_world: np.ndarray, Xw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points (N, 3) -> pixels (N, 2) and depths (N,) in the camera ``T_cam_world``."""
    Xc = Xw @ T_cam_world[:3, :3].T + T_cam_world[:3, 3]
    z = Xc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = (Xc[:, :2] / z[:, None]) * np.array([K[0, 0], K[1, 1]]) + np.array([K[0, 2], K[1, 2]])
    return uv, z


def triangulate(K: np.ndarray, T_cw1: np.ndarray, T_cw2: np.ndarray, uv1: np.ndarray, uv2: np.ndarray) -> np.ndarray:
    """Linear (DLT) triangulation of matched pixels seen from two ``T_cam_world`` poses -> world points (N, 3)."""
    if len(uv1) == 0:
        return np.zeros((0, 3))
    P1 = K @ T_cw1[:3]
    P2 = K @ T_cw2[:3]
    Xh = cv2.triangulatePoints(P1, P2, np.asarray(uv1, np.float64).T, np.asarray(uv2, np.float64).T)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (Xh[:3] / Xh[3]).T


def parallax_deg(T_wc1: np.ndarray, T_wc2: np.ndarray, Xw: np.ndarray) -> np.ndarray:
    """Angle at each point between the rays to the two camera centres, degrees (N,)."""
    a = Xw - T_wc1[:3, 3]
    b = Xw - T_wc2[:3, 3]
    cos = np.sum(a * b, axis=1) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-12)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def good_triangulation(K, T_wc1, T_wc2, uv1, uv2, Xw, max_err_px: float, min_parallax: float) -> np.ndarray:
    """Mask of points in front of both cameras, reprojecting within ``max_err_px`` and with enough parallax."""
    ok = np.isfinite(Xw).all(axis=1)
    for T_wc, uv in ((T_wc1, uv1), (T_wc2, uv2)):
        proj, z = project(K, invert_pose(T_wc), np.where(ok[:, None], Xw, 0.0))
        err = np.linalg.norm(proj - uv, axis=1)
        ok &= (z > 0) & np.isfinite(err) & (err < max_err_px)
    ok &= parallax_deg(T_wc1, T_wc2, np.where(ok[:, None], Xw, 0.0)) >= min_parallax
    return ok


def pose_from_rt(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.ravel(t)
    return T


def pose_jump_depths(T_wc: np.ndarray, refs: tuple[np.ndarray, ...], Xw: np.ndarray) -> float:
    """How far the camera centre of ``T_wc`` lies from the nearest of the reference poses ``refs`` (e.g. the motion
    prediction and the last pose), in median distances of the map points ``Xw`` from the first reference's camera
    centre: scale-free, so one bound fits maps of any (unknown) scale, ratio (inf without a usable point distance)."""
    c = T_wc[:3, 3]
    step = min(float(np.linalg.norm(c - T[:3, 3])) for T in refs)
    depth = float(np.median(np.linalg.norm(np.asarray(Xw, np.float64) - refs[0][:3, 3], axis=1))) if len(Xw) else 0.0
    return step / depth if depth > 0 else (0.0 if step == 0 else float("inf"))
