"""Revisiting old map points at a new keyframe: wide templates warped through the SLAM's relative pose (event-only).

Points last observed before the local window (the landing's first leg, after
its turn) are projected with the new keyframe's pose and looked for in its MCI
by normalised cross-correlation of a wide template (about 31 px) cut from the
MCI of the newest keyframe that observed the point and warped into the new view
through a plane at the point facing the new camera, with the keyframes' SLAM
poses. The wide template carries line ends and corners that break the aperture
ambiguity of a small one, and the warp undoes the in-plane turn of the views,
which a wide template does not tolerate. Matches become keyframe observations
of the old points for the local BA (its keyframes outside the window count as
fixed). Measurements: :mod:`evpose.slam.projection_search`'s docstring.
"""

from __future__ import annotations

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.geometry import project
from evpose.slam.projection_search import ProjectionSearchConfig, cut_patch, search_patch

CONTEXT_MARGIN_PX = 10
"""Extra pixels on each side of the stored context beyond the template: the warp's turn and scale reach into them."""


def context_side(cfg: ProjectionSearchConfig) -> int:
    """Side of the stored context cut, pixels (odd)."""
    return int(cfg.revisit_patch_px) + 2 * CONTEXT_MARGIN_PX


def store_contexts(m: SlamMap, kf_id: int, img8: np.ndarray, cfg: ProjectionSearchConfig) -> None:
    """Give every point observed in keyframe ``kf_id`` the context cut around that observation (the newest view wins;
    nothing while ``cfg.revisit_patch_px`` is 0)."""
    if cfg.revisit_patch_px <= 0:
        return
    side = context_side(cfg)
    for p in m.points.values():
        uv = p.obs.get(kf_id)
        if uv is not None:
            c = cut_patch(img8, uv, side)
            if c is not None:
                p.context, p.context_kf = c, kf_id


def warp_template(context: np.ndarray, K: np.ndarray, T_src_wc: np.ndarray, T_wc: np.ndarray, X: np.ndarray, uv: np.ndarray,
                  size: int) -> np.ndarray:
    """The ``size`` x ``size`` view around ``uv`` in camera ``T_wc`` of the context cut around ``X``'s observation in
    camera ``T_src_wc``, through the plane at ``X`` facing ``T_wc`` (float32). The warp is anchored so the template's
    centre samples the context's centre (the observation), whatever the point's reprojection error there."""
    r = size // 2
    T_cw = invert_pose(T_wc)
    z = float(T_cw[2, :3] @ X + T_cw[2, 3])
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1].astype(np.float64)
    pix = np.stack([xx.ravel() + uv[0], yy.ravel() + uv[1], np.ones(xx.size)])
    Xw = T_wc[:3, :3] @ (np.linalg.solve(K, pix) * z) + T_wc[:3, 3:4]
    Ts = invert_pose(T_src_wc)
    q = K @ (Ts[:3, :3] @ Xw + Ts[:3, 3:4])
    with np.errstate(divide="ignore", invalid="ignore"):
        mx, my = q[0] / q[2], q[1] / q[2]
    c = xx.size // 2
    half = context.shape[0] // 2
    mx = (mx - mx[c] + half).reshape(xx.shape).astype(np.float32)
    my = (my - my[c] + half).reshape(xx.shape).astype(np.float32)
    return cv2.remap(context.astype(np.float32), mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def revisit_points(m: SlamMap, kf: Keyframe, img8: np.ndarray, K: np.ndarray, window: int, cfg: ProjectionSearchConfig) -> int:
    """Search the points of ``m`` last observed before the last ``window`` keyframes in ``kf``'s MCI ``img8`` near their
    projection by ``kf.T_wc``; each unambiguous match becomes the point's observation in ``kf``. Returns how many.

    A match within 2 px of another match or of a point ``kf`` observes already is dropped as a conflict.
    """
    if cfg.revisit_patch_px <= 0 or len(m.keyframes) <= window:
        return 0
    first = m.keyframes[-window:][0].id
    poses = {k.id: k.T_wc for k in m.keyframes}
    pids = [pid for pid, p in sorted(m.points.items())
            if p.context is not None and p.context_kf in poses and p.obs and max(p.obs) < first and kf.id not in p.obs]
    if not pids:
        return 0
    size = int(cfg.revisit_patch_px)
    h, w = img8.shape
    Xw = np.stack([m.points[p].xyz for p in pids])
    proj, z = project(K, invert_pose(kf.T_wc), Xw)
    b = size // 2 + 1
    inside = (z > 0) & (proj[:, 0] >= b) & (proj[:, 0] < w - b) & (proj[:, 1] >= b) & (proj[:, 1] < h - b)
    img = img8.astype(np.float32)
    scfg = ProjectionSearchConfig(min_ncc=cfg.revisit_min_ncc, max_second_ratio=cfg.max_second_ratio, min_texture=cfg.min_texture)
    found_pid, found_uv = [], []
    for i in np.flatnonzero(inside):
        p = m.points[pids[i]]
        tpl = warp_template(p.context, K, poses[p.context_kf], kf.T_wc, p.xyz, proj[i], size)
        if float(tpl.std()) < cfg.min_texture:
            continue
        uv, _ = search_patch(img, tpl, proj[i], int(cfg.revisit_radius_px), scfg)
        if uv is not None:
            found_pid.append(pids[i])
            found_uv.append(uv)
    if not found_pid:
        return 0
    uv = np.array(found_uv)
    keep = np.ones(len(uv), bool)
    if len(uv) > 1:
        d = np.linalg.norm(uv[:, None] - uv[None], axis=2) + np.eye(len(uv)) * 1e9
        keep &= d.min(axis=1) >= 2.0
    taken = np.array([q.obs[kf.id] for q in m.points.values() if kf.id in q.obs], np.float64).reshape(-1, 2)
    if len(taken):
        keep &= np.linalg.norm(uv[:, None] - taken[None], axis=2).min(axis=1) >= 2.0
    for k in np.flatnonzero(keep):
        m.points[found_pid[k]].obs[kf.id] = uv[k].copy()
    return int(keep.sum())
