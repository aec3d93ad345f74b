"""Small multi-view geometry helpers shared by initialisation, tracking and mapping (pinhole, ideal pixels)."""

from __future__ import annotations

import cv2
import numba as nb
import numpy as np

from evpose.core.trajectory import invert_pose


def project(K: np.ndarray, T_cam_world: np.ndarray, Xw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points (N, 3) -> pixels (N, 2) and depths (N,) in the camera ``T_cam_world``."""
    Xc = Xw @ T_cam_world[:3, :3].T + T_cam_world[:3, 3]
    z = Xc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = (Xc[:, :2] / z[:, None]) * np.array([K[0, 0], K[1, 1]]) + np.array([K[0, 2], K[1, 2]])
    return uv, z


def camera_depths(T_wc: np.ndarray, Xw) -> np.ndarray:
    """Depths (z in the camera ``T_wc``, map units) of the world points ``Xw`` (N, 3), in their order."""
    return (np.asarray(Xw, np.float64).reshape(-1, 3) - T_wc[:3, 3]) @ T_wc[:3, 2]


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


@nb.njit(cache=True)
def _rotvec_matrices(rv):
    out = np.empty((rv.shape[0], 3, 3))
    for i in range(rv.shape[0]):
        x0, y0, z0 = rv[i, 0], rv[i, 1], rv[i, 2]
        angle = np.sqrt(x0 * x0 + y0 * y0 + z0 * z0)
        if angle <= 1e-3:  # scipy's Taylor series of sin(angle / 2) / angle
            a2 = angle * angle
            scale = 0.5 - a2 / 48 + a2 * a2 / 3840
        else:
            scale = np.sin(angle / 2) / angle
        x, y, z, w = scale * x0, scale * y0, scale * z0, np.cos(angle / 2)
        x2, y2, z2, w2 = x * x, y * y, z * z, w * w
        xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
        out[i, 0, 0] = x2 - y2 - z2 + w2
        out[i, 1, 0] = 2 * (xy + zw)
        out[i, 2, 0] = 2 * (xz - yw)
        out[i, 0, 1] = 2 * (xy - zw)
        out[i, 1, 1] = -x2 + y2 - z2 + w2
        out[i, 2, 1] = 2 * (yz + xw)
        out[i, 0, 2] = 2 * (xz + yw)
        out[i, 1, 2] = 2 * (yz - xw)
        out[i, 2, 2] = -x2 - y2 + z2 + w2
    return out


def rotvec_matrices(rotvecs: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of the rotation vectors ``rotvecs`` (N, 3), rad: bit for bit scipy's
    ``Rotation.from_rotvec(rotvecs).as_matrix()`` (its quaternion, small-angle series and matrix, scipy 1.17; the
    reference in ``tests/slam/test_geometry_rotvec.py``) without its per-call overhead (session 26: 10-15 us a call,
    called some 15 times per MCI by the MCI's warps)."""
    return _rotvec_matrices(np.ascontiguousarray(np.asarray(rotvecs, np.float64).reshape(-1, 3)))
