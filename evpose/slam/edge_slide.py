"""Birth-patch structure tensors, and tracks that slide along the edge they were born on (``FeatureConfig.klt_edge_slide_px``,
``klt_edge_follow_max_ratio``, ``blob_max_quality``; all off).

Session 41 (pnp41) found a third of the event-only PnP inliers 3-20 px off their birth point's true projection, two
thirds of them ahead along the image motion. Is that the aperture problem? Session 42 (drift42, ``/tmp/s42/drift42``:
``h.py`` is pnp41's harness also recording the structure tensor of the birth MCI at each new track's birth pixel,
Sobel gradients summed over 23 and 11 px squares, and the Shi-Tomasi score (blockSize 5) as a share of the image's
best, the quantity ``min_eigen_quality`` gates; ``st.py`` the tables, ``diag_*.txt`` its output; main's defaults, indoor
seeds 0-8, landing 0-4, every inlier of every PnP estimate against its birth point's true projection). The DIRECTION is
the aperture: a drifting inlier's error (3-20 px off) lies along the edge of its birth patch (the structure tensor's
minor eigenvector), |cos| mean 0.76 on the landing / 0.78 indoors, 59 / 61 % within 30 deg, against 0.637 and 33 % for
directions uniform in angle (inliers 0.5-3 px off: 0.69 / 0.71); per track (its last inlier observation) 0.79 / 0.76,
and 0.93-0.95 / 0.89-0.92 for the most edge-like fifth (eigenvalue ratio under 0.02-0.05); against the edge of the
CURRENT MCI at the track only 0.66 on the landing (0.77 indoors), which is why the current tensor's along-edge sigma of
``TrackingConfig.ba_edge_along_sigma_px`` could not see it. It is the track's own slide, not its neighbours': the
error minus the median error of its 8 nearest inliers is still a median 4.6 / 4.8 px (71 / 70 % of drifting inliers
still over 3 px), and that residual lies along the birth edge as much (0.78 / 0.76). But the drift is NOT concentrated
on edge-like tracks: per track, the share drifting by quintile of the birth eigenvalue ratio (23 px), landing 0.43 /
0.51 / 0.35 / 0.40 / 0.62, indoor 0.47 / 0.34 / 0.37 / 0.55 / 0.76 (quintile edges landing 0.015 / 0.061 / 0.12 / 0.37,
indoor 0.05 / 0.16 / 0.39 / 0.82): the near-isotropic patches drift most, and in no preferred direction (|cos| 0.60-0.61)
-- a right-angle corner is isotropic too, but those drifting are weak dots: with a Shi-Tomasi share under 0.0118 (the
lower two thirds) the patches above 0.4 drift 0.67-0.83 of the time, above 0.0118 0.17-0.52. By the Shi-Tomasi share,
the strongest fifth drifts least (landing 0.28, indoor 0.31-0.33 against 0.44-0.61 for the rest). The drift grows with
age (Spearman |e| vs age +0.44 landing, +0.34-0.38 indoor; vs eigenvalue ratio -0.07 / +0.15). OpenCV's KLT minimum
eigenvalue per step (``FeatureConfig.klt_min_eig``, recorded by ``KLTREC=1``): indoor seed 9, 23 px windows, quantiles
1 / 5 / 10 / 25 / 50 % 0.00012 / 0.00023 / 0.00033 / 0.00085 / 0.0048; landing seed 2 on the sensor grid 0.00028 /
0.00081 / 0.0017 / 0.0081 / 0.026, on the fine grid (35 px) 0.00014 / 0.00034 / 0.00056 / 0.0013 / 0.0029.

What was tried (ATE of ``evpose eval --atlas --correct-scale``, paired per recording against main's defaults; runs by
``/tmp/s42/drift42/runner.sh``, sums by ``pair.py``; the step shortness h_rel of pnp41's ``ana2.py``, mean over the
PnP-placed keyframes, by ``hrel.py``; main: indoor 0-8 -0.270 +- 0.075 (85 keyframes), landing 0-4 -0.118 +- 0.020
(130)): see the fields' docstrings. In short: ending (or renewing) the tracks that slide past 4-8 px shortens the
short steps (h_rel landing -0.074 to -0.098, indoor -0.12 to -0.25) but moves the ATE only within its scatter, with a
runaway here and there (indoor 0-18 -0.10 to +0.27 points, landing 0-4 -0.21 to +1.39); following the neighbours along
the edge, gating weak dots or weak corners at detection, or a higher KLT eigenvalue floor are no better. Forward-backward KLT is already on (``klt_max_bidir_error_px``), and a higher
``min_eigen_quality`` (detection's Shi-Tomasi gate) 0.004: indoor 0-7 2.006 -> 3.035 % (+1.03 +- 1.45, 3 better; seed 3
1.31 -> 12.15 %), landing 0-2 1.331 -> 1.704 % (+0.37 +- 0.74), h_rel indoor -0.349, landing -0.122.
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
        return self.slid(prev8, ids, uv, new, ok, cfg)[0]

    def slid(self, prev8: np.ndarray, ids: np.ndarray, uv: np.ndarray, new: np.ndarray, ok: np.ndarray,
             cfg: FeatureConfig) -> tuple[np.ndarray, np.ndarray]:
        """(``ok`` without the tracks that slid past ``cfg.klt_edge_slide_px``, those tracks' mask); see :meth:`check`."""
        self._register(prev8, ids, uv, cfg.klt_window_px)
        ok_in, ok = ok, ok.copy()
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
        return ok, np.asarray(ok_in, bool) & ~ok

    def step(self, fe, new: np.ndarray, ok: np.ndarray, cfg: FeatureConfig) -> np.ndarray:
        """:meth:`slid` on the front end ``fe``'s step into ``new`` (``fe.prev8``, ``fe.ids``, ``fe.uv`` before it);
        returns ``ok`` without the slid tracks, or with ``cfg.klt_edge_slide_renew`` keeps them under new ids of
        ``fe`` (``fe.ids`` replaced, ``fe.next_id`` advanced)."""
        ok, slid = self.slid(fe.prev8, fe.ids, fe.uv, new, ok, cfg)
        if cfg.klt_edge_slide_renew and slid.any():
            n = int(slid.sum())
            fe.ids = fe.ids.copy()
            fe.ids[slid] = np.arange(fe.next_id, fe.next_id + n, dtype=np.int64)
            fe.next_id += n
            ok = ok | slid
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
