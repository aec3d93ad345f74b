"""Affine template refinement of KLT tracks (``FeatureConfig.affine_refine``).

MCI-to-MCI KLT models each step as a pure translation of a 23 px window, while the simulated landing's descent and
turn scale, rotate and shear a corner's patch between its birth MCI and later ones. Here each live track keeps the
patch it was born on (blurred, float) and, after every KLT step, that reference patch is aligned to the current MCI
by OpenCV's enhanced-correlation-coefficient maximisation with an affine warp (:func:`cv2.findTransformECC`,
invariant to the brightness gain and offset of the normalised event images), started at the KLT position and at
the track's previous affine carried forward by the Jacobian of the step's RANSAC homography of all tracks. The track
moves to the aligned centre when the alignment converges, correlates at least ``affine_min_cc`` and lands within
``affine_max_shift_px`` of KLT's result; otherwise it keeps KLT's position.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from evpose.slam.config import FeatureConfig


def blurred(img8: np.ndarray, sigma_px: float) -> np.ndarray:
    """``img8`` as float32, Gaussian-blurred by ``sigma_px`` (none at 0)."""
    f = np.asarray(img8, np.float32)
    return cv2.GaussianBlur(f, (0, 0), float(sigma_px)) if sigma_px > 0 else f


def cut_template(img: np.ndarray, uv: np.ndarray, patch_px: int) -> np.ndarray | None:
    """The ``patch_px`` square (odd) of ``img`` centred on the sub-pixel ``uv`` (bilinear), float32; None near the border."""
    h, w = img.shape
    r = patch_px // 2
    if not (r + 1 <= uv[0] < w - r - 2 and r + 1 <= uv[1] < h - r - 2):
        return None
    return cv2.getRectSubPix(img, (patch_px, patch_px), (float(uv[0]), float(uv[1])))


def align_template(template: np.ndarray, img: np.ndarray, uv: np.ndarray, A: np.ndarray, margin_px: int,
                   iterations: int = 30, affine: bool = True) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Affine ECC alignment of ``template`` (centred on its middle pixel) into ``img`` near ``uv`` from the linear part ``A``
    (``affine`` False: ``A`` held, only the translation fitted).

    Returns (the template centre's position in ``img`` (2,), the new linear part (2, 2), the correlation) or None
    when the search region leaves the image, the template is flat or ECC fails to converge.
    """
    p = template.shape[0]
    c = (p - 1) / 2.0
    half = c + margin_px
    h, w = img.shape
    x0, y0 = int(np.floor(uv[0] - half)), int(np.floor(uv[1] - half))
    size = int(np.ceil(2 * half)) + 2
    if x0 < 0 or y0 < 0 or x0 + size > w or y0 + size > h:
        return None
    region = np.ascontiguousarray(img[y0:y0 + size, x0:x0 + size])
    t = np.array([uv[0] - x0, uv[1] - y0]) - A @ np.array([c, c])
    warp = np.hstack([A, t[:, None]]).astype(np.float32)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, int(iterations), 1e-4)
    try:
        cc, warp = cv2.findTransformECC(template, region, warp, cv2.MOTION_AFFINE if affine else cv2.MOTION_TRANSLATION, crit, None, 1)
    except cv2.error:
        return None
    Wm = warp.astype(np.float64)
    centre = Wm[:, :2] @ np.array([c, c]) + Wm[:, 2] + np.array([x0, y0])
    return centre, Wm[:, :2], float(cc)


def homography_jacobians(H: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Jacobians (N, 2, 2) of the homography ``H`` at the points ``uv`` (N, 2)."""
    x, y = uv[:, 0], uv[:, 1]
    den = H[2, 0] * x + H[2, 1] * y + H[2, 2]
    u = (H[0, 0] * x + H[0, 1] * y + H[0, 2]) / den
    v = (H[1, 0] * x + H[1, 1] * y + H[1, 2]) / den
    J = np.empty((len(uv), 2, 2))
    J[:, 0, 0] = (H[0, 0] - u * H[2, 0]) / den
    J[:, 0, 1] = (H[0, 1] - u * H[2, 1]) / den
    J[:, 1, 0] = (H[1, 0] - v * H[2, 0]) / den
    J[:, 1, 1] = (H[1, 1] - v * H[2, 1]) / den
    return J


@dataclass
class AffineTracks:
    """Per track id: its reference patch (float32) and the linear part of its affine from that patch to the newest MCI."""

    templates: dict = field(default_factory=dict)
    linear: dict = field(default_factory=dict)
    age: dict = field(default_factory=dict)
    """Track id -> MCI-to-MCI steps since its reference patch was cut."""
    stats: list = field(default_factory=lambda: [0, 0, 0])
    """Counts over the run: tracks tried, tracks moved, tracks whose alignment was refused."""

    def adopt(self, ids: np.ndarray, uv: np.ndarray, img: np.ndarray, cfg: FeatureConfig) -> None:
        """Cut the reference patch of every track in ``ids`` that has none yet from ``img`` (the MCI it was born on)."""
        for tid, p in zip(ids.tolist(), uv):
            if tid not in self.templates:
                tpl = cut_template(img, p, int(cfg.affine_patch_px) | 1)
                self.templates[tid] = tpl
                self.linear[tid] = np.eye(2)
                self.age[tid] = 0

    def refine(self, ids: np.ndarray, p0: np.ndarray, p1: np.ndarray, ok: np.ndarray, prev: np.ndarray, img: np.ndarray,
               cfg: FeatureConfig) -> np.ndarray:
        """KLT's step ``p0`` (in ``prev``) -> ``p1`` (in ``img``) of the ``ok`` tracks refined by aligning each track's
        reference patch (``affine_previous``: the patch around ``p0`` in ``prev``) to ``img``; returns the new ``p1``."""
        out = p1.copy()
        idx = np.flatnonzero(ok)
        J = None
        if len(idx) >= 8:
            H, _ = cv2.findHomography(np.ascontiguousarray(p0[idx], np.float64), np.ascontiguousarray(p1[idx], np.float64),
                                      cv2.RANSAC, 2.0)
            if H is not None:
                J = homography_jacobians(H, p0[idx].astype(np.float64))
        margin = int(np.ceil(cfg.affine_max_shift_px)) + 2
        for j, i in enumerate(idx.tolist()):
            tid = int(ids[i])
            if cfg.affine_previous:
                tpl = cut_template(prev, p0[i].astype(np.float64), int(cfg.affine_patch_px) | 1)
                self.linear[tid] = np.eye(2)
            else:
                tpl = self.templates.get(tid)
            if tpl is None:
                continue
            A = self.linear[tid] if J is None else J[j] @ self.linear[tid]
            self.age[tid] = self.age.get(tid, 0) + 1
            if self.age[tid] < cfg.affine_min_age:
                self.linear[tid] = A
                continue
            self.stats[0] += 1
            res = align_template(tpl, img, p1[i].astype(np.float64), A, margin, int(cfg.affine_iterations), cfg.affine_fit_linear)
            if res is None or res[2] < cfg.affine_min_cc or np.hypot(*(res[0] - p1[i])) > cfg.affine_max_shift_px:
                self.stats[2] += 1
                self.linear[tid] = A
                continue
            out[i] = res[0]
            self.linear[tid] = res[1]
            self.stats[1] += 1
        return out

    def prune(self, ids: np.ndarray) -> None:
        """Forget the tracks not in ``ids``."""
        live = set(ids.tolist())
        for tid in [t for t in self.templates if t not in live]:
            del self.templates[tid]
            del self.linear[tid]
            self.age.pop(tid, None)
