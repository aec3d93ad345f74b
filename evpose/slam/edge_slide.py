"""Ending MCI-to-MCI tracks that slide along the edge they were born on (``FeatureConfig.klt_edge_slide_px``, off).

Session 41 (pnp41) found a third of the event-only PnP inliers 3-20 px off their birth point's true projection, two
thirds of them ahead along the image motion. Session 42 (drift42, ``/tmp/s42/drift42/st.py``: the structure tensor of
the birth MCI over 23 / 11 px squares at the birth pixel, against each inlier's error from its birth point's true
projection): the drift lies along the edge the track was born on, the aperture problem: the |cos| between a
drifting track's error (3-20 px) and its birth edge direction is a mean 0.76-0.78 (59-61 % within 30 deg; directions
uniform in angle give 0.637 and 33 %), 0.87-0.91 for the most edge-like fifth (eigenvalue ratio under 0.05); against
the current MCI's edge direction only 0.65 on the landing. But the drift is not concentrated on edge-like patches.

Here each track keeps the edge direction of its birth patch (the minor eigenvector of the structure tensor over the
KLT window in the MCI it is first stepped from) and, over its MCI-to-MCI steps, the sum of its step's component along
that direction minus the same component of the median step of its ``klt_edge_slide_neighbours`` nearest live tracks;
a track whose sum exceeds ``klt_edge_slide_px`` is ended (its map point stays for the projection search).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.spatial import cKDTree

from evpose.slam.feature_config import FeatureConfig


def structure_tensor(img8: np.ndarray, uv: np.ndarray, window_px: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Jxx, Jxy, Jyy) at the nearest pixels of ``uv``: the Sobel gradients' products summed over the ``window_px``
    square (odd) of ``img8``, float64 (N,) each."""
    f = img8.astype(np.float32)
    gx = cv2.Sobel(f, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(f, cv2.CV_32F, 0, 1, ksize=3)
    h, w = f.shape
    iu = np.clip(np.round(uv[:, 0]).astype(int), 0, w - 1)
    iv = np.clip(np.round(uv[:, 1]).astype(int), 0, h - 1)
    k = int(window_px) | 1
    jxx, jxy, jyy = (cv2.boxFilter(a, -1, (k, k), normalize=False, borderType=cv2.BORDER_CONSTANT)[iv, iu].astype(np.float64)
                     for a in (gx * gx, gx * gy, gy * gy))
    return jxx, jxy, jyy


def edge_directions(img8: np.ndarray, uv: np.ndarray, window_px: int) -> np.ndarray:
    """Unit edge direction (N, 2) at ``uv`` in ``img8``: the minor eigenvector of :func:`structure_tensor` (the
    direction along which the patch changes least)."""
    jxx, jxy, jyy = structure_tensor(img8, uv, window_px)
    th = 0.5 * np.arctan2(2.0 * jxy, jxx - jyy)  # the dominant gradient's direction; the edge runs across it
    return np.c_[-np.sin(th), np.cos(th)]


def tensor_ratio(img8: np.ndarray, uv: np.ndarray, window_px: int) -> np.ndarray:
    """Smaller over larger eigenvalue of :func:`structure_tensor` at ``uv`` (0: a straight edge, 1: isotropic; 1 where
    the square is flat), (N,)."""
    jxx, jxy, jyy = structure_tensor(img8, uv, window_px)
    tr, d = jxx + jyy, np.sqrt(((jxx - jyy) / 2) ** 2 + jxy ** 2)
    l1 = tr / 2 + d
    return np.where(l1 > 0, np.maximum(tr / 2 - d, 0.0) / np.where(l1 > 0, l1, 1.0), 1.0)


@dataclass
class EdgeSlide:
    """Each live track's birth edge direction and its summed along-edge slide against its neighbours."""

    state: dict = field(default_factory=dict)
    """Track id -> [edge direction (2,) float64, summed slide px, birth eigenvalue ratio]."""

    def _register(self, prev8: np.ndarray, ids: np.ndarray, uv: np.ndarray, window_px: int) -> None:
        unseen = np.array([int(t) not in self.state for t in ids.tolist()], bool)
        if unseen.any():
            p = np.asarray(uv, np.float64)[unseen]
            for t, d, r in zip(ids[unseen].tolist(), edge_directions(prev8, p, window_px), tensor_ratio(prev8, p, window_px)):
                self.state[int(t)] = [d, 0.0, float(r)]

    def _neighbour_steps(self, uv: np.ndarray, new: np.ndarray, idx: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(each track's step, the median step of its ``k`` nearest other tracks), over the tracks ``idx``."""
        p = np.asarray(uv, np.float64)[idx]
        step = np.asarray(new, np.float64)[idx] - p
        _, nn = cKDTree(p).query(p, k=k + 1)
        return step, np.median(step[nn[:, 1:]], axis=1)  # the first neighbour is the track itself

    def check(self, prev8: np.ndarray, ids: np.ndarray, uv: np.ndarray, new: np.ndarray, ok: np.ndarray,
              cfg: FeatureConfig) -> np.ndarray:
        """``ok`` with the tracks whose summed along-edge slide now exceeds ``cfg.klt_edge_slide_px`` ended; ``uv`` are
        the tracks' positions in ``prev8`` (the MCI stepped from), ``new`` in the current MCI. Forgets dead tracks."""
        self._register(prev8, ids, uv, cfg.klt_window_px)
        ok = ok.copy()
        idx = np.flatnonzero(ok)
        k = int(cfg.klt_edge_slide_neighbours)
        if len(idx) > k:
            step, ref = self._neighbour_steps(uv, new, idx, k)
            for j, i in enumerate(idx.tolist()):
                s = self.state[int(ids[i])]
                s[1] += float((step[j] - ref[j]) @ s[0])
                if abs(s[1]) > cfg.klt_edge_slide_px:
                    ok[i] = False
        self._forget(ids[ok])
        return ok

    def follow(self, prev8: np.ndarray, ids: np.ndarray, uv: np.ndarray, new: np.ndarray, ok: np.ndarray,
               cfg: FeatureConfig) -> np.ndarray:
        """``new`` with each live track born on an edge (birth eigenvalue ratio below ``cfg.klt_edge_follow_max_ratio``)
        given, along its birth edge direction, the step of its ``klt_edge_slide_neighbours`` nearest live tracks' median
        step instead of its own (KLT measures only the step across an edge). Forgets dead tracks."""
        self._register(prev8, ids, uv, cfg.klt_window_px)
        out = np.array(new, copy=True)
        idx = np.flatnonzero(ok)
        k = int(cfg.klt_edge_slide_neighbours)
        if len(idx) > k:
            step, ref = self._neighbour_steps(uv, new, idx, k)
            for j, i in enumerate(idx.tolist()):
                d, _, r = self.state[int(ids[i])]
                if r < cfg.klt_edge_follow_max_ratio:
                    out[i] = out[i] - ((step[j] - ref[j]) @ d) * d
        self._forget(ids[ok])
        return out.astype(np.asarray(new).dtype)

    def _forget(self, live_ids: np.ndarray) -> None:
        live = {int(t) for t in live_ids.tolist()}
        self.state = {t: s for t, s in self.state.items() if t in live}
