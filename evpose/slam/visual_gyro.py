"""A visual gyro for event-only coasting: the camera rotation between consecutive MCIs from their edges.

An event-only map that loses its tracks coasts on the rotation rate of its own recent poses
(:mod:`evpose.slam.event_coasting`), and indoors that rate is off by degrees within a tenth of a second (the room
turns at up to ~130 deg/s^2). The MCIs keep showing the edges the camera sweeps past even while KLT loses them, so
the rotation since the previous MCI is measured here: the previous MCI's edge pixels, rotated about the camera centre,
are laid onto a distance field of the current MCI's edges (Levenberg-Marquardt, Huber weights). The translation is
not modelled: its flow (indoors about as large as the rotation's, ~1 px per MCI) is taken up by the rotation, which
keeps the coasted pose's image of the scene where the events put it.

Measured (session 18, ``/tmp/s18/edgealign9``; off by default). Per MCI step (indoor seed 0, 22 pairs): 0.34 deg
median error at a median step of 0.46 deg, biased (mean error 0.38 deg per step, mostly about the vertical axis: the
camera moves 9 mm per MCI at 1.24 m/s); with the true translation and the edges on a plane at 2.5 m, 0.17 deg and a
0.09 deg bias. Coasted rotation against the truth, relative to the last tracked pose (indoor seeds 0-3, ``coast.py``;
0-50 / 50-150 / 150-400 ms after it, median and 90th percentile): constant rate 1.50 / 4.56 / 15.6 deg (7.4 / 12.4 /
37.2), visual gyro 0.86 / 3.01 / 8.15 deg (1.7 / 5.2 / 14.4). In the system, indoor seeds 0-7 under the defaults and
the neutral perturbations ``ba_huber_px`` 1.9 / 2.1 and ``reprojection_threshold_px`` 2.4 (32 runs): ATE 7.48 -> 4.46
% (paired -3.02 +- 0.60 s.e. points, better in 26, 3 runs within 2 % against none), but tracked from the events 42.6
-> 30.5 % (paired -12.1 +- 1.2), tracked 92.8 -> 90.2 % (least 80.8 -> 79.1), maps 117 -> 154, median RPE 0.0351 ->
0.0422 m/m, CPU per MCI median 15.0 -> 20.0 ms (runs not paired under the shared load): maps coast longer instead of
being re-placed, and the ATE, summed per map, gains from the shorter maps (the 7 runs with as many maps either way:
7.30 -> 6.65 %, better in 3). Held-out indoor seeds 8-11 (defaults): ATE 8.59 -> 5.07 %, from the events 40.3 -> 34.3
%, maps 14 -> 18. Landing event-only seeds 0-11: 1.97 %, 8 of 12 within 2 % (as without it); held-out seeds 24-35:
2.99 -> 3.24 %, 5 -> 4 within 2 % (seed 29 1.95 -> 4.91 % from one coasted MCI). Event-inertial runs never use it
(E-I-C2 landing seeds 0 and 1 bit-identical). Variants: also as the rotation of the pose prediction of tracked MCIs
3.92 % / 32.7 % from the events (defaults, seeds 0-7; this and the last variant with an earlier, Gauss-Newton
alignment); with the translation modelled (the map's camera-frame velocity, the edges on a plane at the map points'
median depth) 7.98 % / 47.4 %, with ``ProjectionSearchConfig.prepass_below`` 12 (rotation only) 4.87 % / 32.3 %.

Why it lowers the share tracked from the events (session 28, ``/tmp/s28/gyro28``; details in the module notes of
:mod:`evpose.slam.event_coasting`). Not by holding a coast 'valid' longer: by default 68 % of the coasts end with the
map placed again by PnP within a few MCIs, on points triangulated at the coast's own keyframes (17 of the 22 it uses),
whose parallax the coast's rotation error made; the gyro's rotation, twice as near the truth, leaves too little
parallax to triangulate (7 % of the tried tracks become points, against 18 %), the map starves and is lost when
``coast_s`` runs out (15 % of its coasts placed again). Over the 40 runs of indoor seeds 0-7 under the defaults and the
four neutral perturbations: ATE 7.63 -> 3.95 %, from the events 41.9 -> 28.5 %, maps 149 -> 200; on the stretches both
runs track as one map the error does not change (0.5 s windows inside one map: 5.35 -> 5.34 %; fixed 0.5 s segments
without a map change 6.87 -> 6.69 %), and a coast turning by the true rotation does no better there (5.85 -> 7.78 %,
8.13 -> 8.48 %). Held-out indoor seeds 8-11 (20 runs): ATE 8.33 -> 4.33 %, from the events 43.9 -> 33.1 %, maps 67 ->
95, coasts placed again 75 -> 17 %; segments without a map change 7.53 -> 6.92 % (-0.61 +- 0.43, 44). Kept off: with
the map placed again as often as by default (the gyro only after 50 / 100 ms of coast; a starved MCI placed from its
few tracked points with the measured rotation) the ATE gain is gone (seeds 0-7: 7.35 / 8.04 / 7.84 % against 6.84);
re-turning only the coasts that end lost (same maps and share) 7.63 -> 7.74 % over the 40 runs. Coasted keyframes
that triangulate nothing (``TrackingConfig.coast_triangulate`` off, no gyro) do what the gyro does, and more: 40 runs
3.29 %, from the events 26.1 %, 213 maps.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.ndimage import distance_transform_edt
from scipy.spatial.transform import Rotation


@dataclass
class VisualGyroConfig:
    """Rotation between consecutive MCIs from their edges, used by event-only coasting."""

    enabled: bool = False
    """Event-only maps coast on the measured rotation since the previous MCI instead of the constant rate of their
    recent poses. Off: indoors it halves the coast's rotation error but lowers the share of time tracked from the
    events by 12 points, and its lower ATE comes mostly from more, shorter maps (measurements in the module's
    docstring). Session 27 (``/tmp/s27/turn27``, module notes of :mod:`evpose.slam.event_coasting`), indoor seeds 0-7 on
    that session's defaults: 6.84 -> 3.23 % (8 of 8 better), from the events 40.8 -> 27.6 %, maps 30 -> 40; a coast
    turning by the true rotation (a perfect gyro) 4.83 % with 35 maps. Session 28: the lower share is the map no longer
    placed again after a coast on points the coast's own rotation error triangulated; where both runs track as one map
    the error is unchanged (module docstring). Session 37 on session 36's defaults (coasted keyframes triangulate
    nothing, so coasts seldom re-place a map; ``/tmp/s37/eo37``, tag ``vg``, paired against ``m35``): indoor 0-19 2.161
    -> 1.822 % (-0.339 +- 0.200, 12 of 20 better), held-out 20-39 2.159 -> 2.143 (-0.016 +- 0.201), 40-53 2.064 -> 1.771
    (-0.292 +- 0.176), landing 0-23 1.474 -> 1.554 (+0.079 +- 0.053, 3 worse, none better); the online coast changes the
    MCIs' warp priors and with them every later map. ``written_coasts`` keeps its gain without that."""
    written_coasts: bool = True
    """Event-only: each coasted pose of a young map is written (the map's output trajectory) as the coast would have
    placed it on the measured rotations, chained over the written poses, while tracking coasts on as without it
    (bit-identical maps, statuses and tracked time); ignored with ``enabled`` (which coasts on them online). Why:
    :mod:`evpose.slam.written_coast`. Session 37 (``/tmp/s37/eo37``: ``run.py`` / ``batch.sh`` = session 35's harness,
    ``evpose slam`` + ``evpose eval --atlas --correct-scale``; ``sum.py m35 fin``, paired against session 36's defaults,
    tag ``m35``; ``maps.py`` splits the ATE by map class): indoor 0-19 2.161 -> 1.888 % (-0.273 +- 0.096, 15 of 20
    better), held-out 20-39 2.159 -> 1.915 (-0.244 +- 0.080, 14 better), 40-53 2.064 -> 1.828 (-0.236 +- 0.134, 7
    better, 7 worse); over 0-53 median 1.867 -> 1.720 %, within 2 % 29 -> 43 of 54; landing 0-23 bit-identical (1.474
    %). The gain is in the maps with at most two PnP poses before their coast: 0.646 -> 0.385 / 0.768 -> 0.529 / 0.753
    -> 0.505 points of 0-19 / 20-39 / 40-53 (the true rotation rate held, an oracle, 0.361 on 0-19). Seed 53 still
    tracks 79.1 %, the others at least 80.5 % (unchanged). Without
    ``written_coasts_max_map_s`` (tag ``wc``) the indoor figures are the same to 0.001 and the landing 1.474 -> 1.477
    (+0.003 +- 0.003: seed 4's 2.4 s map coasting at its end 7.09 -> 7.17 %). Writing each pose at the mean of the old and
    measured orientations (``coasting.coast_pose``, tag ``wcmid``, 15 seeds of 0-19): +0.013 +- 0.007 against this, not
    kept. Cost: the visual gyro on each coasted MCI of a young map; main-thread CPU per MCI (``cpu.py``, indoor seed
    0, one run each) coasted MCIs median 6.7 -> 15.1 ms (90th percentile 13.0 -> 20.1, most 19.9 -> 28.2), all MCIs
    median 8.0 -> 15.1, tracked MCIs unchanged (16.6). Figures measured with this exact distance field (scipy's: with
    OpenCV's the written poses differed run to run in the 9th digit); tags ``wc`` / ``wcg`` were run with OpenCV's and
    agree with ``fin`` (this) to 0.001 points."""
    written_coasts_max_map_s: float = field(default=0.5, metadata={"min": 0.0, "max": 10.0, "step": 0.05, "unit": "s"})
    """With ``written_coasts``: only a map whose trajectory up to its last PnP pose spans less than this writes its
    coast on the measured rotations (0: every map), seconds. 0.5 as ``TrackingConfig.coast_triangulate_min_map_s``:
    the landing's mature maps keep their slow, steady coasts (figures above)."""
    edge_fraction: float = field(default=0.25, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Edge pixels are ridge pixels of the MCI at or above this share of its robust maximum (99.5th percentile of the
    non-zero pixels), ratio."""
    max_distance_px: float = field(default=8.0, metadata={"min": 1.0, "max": 50.0, "step": 0.5, "unit": "px"})
    """The distance field is clipped here (farther pixels pull no more), pixels."""
    huber_px: float = field(default=1.5, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Huber threshold of the distance to the nearest edge, pixels."""
    iterations: int = field(default=15, metadata={"min": 1, "max": 100, "step": 1, "unit": "iterations"})
    """Levenberg-Marquardt iterations, iterations."""
    inlier_px: float = field(default=1.5, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """An edge pixel of the previous MCI lands on an edge when the rotation puts it this close to one, pixels."""
    min_inlier_ratio: float = field(default=0.5, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """The rotation is accepted when at least this share of the previous MCI's edge pixels land on edges, ratio."""
    max_edge_pixels: int = field(default=1500, metadata={"min": 50, "max": 20000, "step": 50, "unit": "px"})
    """At most this many edge pixels of the previous MCI are used (an even stride in raster order), pixels."""
    min_edge_pixels: int = field(default=100, metadata={"min": 10, "max": 5000, "step": 10, "unit": "px"})
    """Fewer edge pixels in view than this and no rotation is measured, pixels."""
    border_px: int = field(default=4, metadata={"min": 1, "max": 50, "step": 1, "unit": "px"})
    """Pixels this close to the image border are left out, pixels."""


@dataclass
class EdgeField:
    """Clipped, lightly blurred distance to the nearest edge pixel and its gradient, float32 (H, W) each."""

    dist: np.ndarray
    gx: np.ndarray
    gy: np.ndarray


def ridge_mask(img: np.ndarray, threshold: float) -> np.ndarray:
    """Pixels at or above ``threshold`` that are a peak across their ridge (along x or along y).

    A thresholded splat image is a band a few pixels wide, at distance zero throughout, where an alignment has no
    gradient and stops anywhere inside; its crest is the edge.
    """
    p = np.pad(img, 1, mode="edge")  # the border is no peak
    c = p[1:-1, 1:-1]

    def peak(a, b):  # a maximum between its two neighbours, strictly above one of them (a flank is flat along its edge)
        return (c >= a) & (c >= b) & ((c > a) | (c > b))

    return (c >= threshold) & (c > 0) & (peak(p[1:-1, :-2], p[1:-1, 2:]) | peak(p[:-2, 1:-1], p[2:, 1:-1]))


def _edges(image8: np.ndarray, cfg: VisualGyroConfig) -> np.ndarray | None:
    img = np.asarray(image8, np.float32)
    nz = img[img > 0]
    if nz.size == 0:
        return None
    return ridge_mask(img, cfg.edge_fraction * float(np.percentile(nz, 99.5)))


def edge_field(image8: np.ndarray, cfg: VisualGyroConfig) -> EdgeField | None:
    """Distance field of the image's edge pixels (None for an empty image)."""
    edges = _edges(image8, cfg)
    if edges is None:
        return None
    # The exact Euclidean distance: scipy's, not OpenCV's DIST_MASK_PRECISE, whose result changed in the last bits from
    # call to call on the same image (session 37; up to 4e-6 px), which a coast chained over the measured rotations
    # carried into every later pose.
    if not edges.any():
        return None  # nothing to align with (scipy, unlike OpenCV, has no "far from everything" for an empty mask)
    dist = distance_transform_edt(~edges).astype(np.float32)
    dist = np.minimum(dist, np.float32(cfg.max_distance_px))
    # A light blur rounds the kink on the crest, so the alignment settles on it instead of hopping across.
    dist = cv2.GaussianBlur(dist, (5, 5), 1.0)
    gx = cv2.Sobel(dist, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(dist, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    return EdgeField(dist, gx, gy)


def edge_bearings(image8: np.ndarray, K: np.ndarray, cfg: VisualGyroConfig) -> np.ndarray:
    """Bearings (N, 3), z = 1, of the image's edge pixels away from the border, at most ``max_edge_pixels``."""
    edges = _edges(image8, cfg)
    if edges is None:
        return np.zeros((0, 3))
    b = cfg.border_px
    edges[:b], edges[-b:], edges[:, :b], edges[:, -b:] = False, False, False, False
    v, u = np.nonzero(edges)
    if len(u) > cfg.max_edge_pixels:
        keep = np.linspace(0, len(u) - 1, cfg.max_edge_pixels).astype(np.int64)
        u, v = u[keep], v[keep]
    return np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(len(u))], axis=1)


def _bilinear(img: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    u0 = np.floor(u).astype(np.int64)
    v0 = np.floor(v).astype(np.int64)
    fu, fv = u - u0, v - v0
    return ((1 - fu) * (1 - fv) * img[v0, u0] + fu * (1 - fv) * img[v0, u0 + 1]
            + (1 - fu) * fv * img[v0 + 1, u0] + fu * fv * img[v0 + 1, u0 + 1])


def _project(K: np.ndarray, R: np.ndarray, B: np.ndarray, shape: tuple[int, int], border: int):
    """Bearings ``B`` of the previous camera seen from one rotated by ``R``: (camera points, u, v, in-view mask)."""
    Xc = B @ R  # R^T b per row
    z = Xc[:, 2]
    ok = z > 1e-6
    with np.errstate(divide="ignore", invalid="ignore"):
        u = K[0, 0] * Xc[:, 0] / z + K[0, 2]
        v = K[1, 1] * Xc[:, 1] / z + K[1, 2]
    h, w = shape
    ok &= (u >= border) & (u < w - 1 - border) & (v >= border) & (v < h - 1 - border)
    return Xc, u, v, ok


def align_rotation(field_: EdgeField, K: np.ndarray, B: np.ndarray, R_guess: np.ndarray,
                   cfg: VisualGyroConfig) -> tuple[np.ndarray | None, int, int]:
    """Rotation ``R_prev_cur`` laying the previous camera's edge bearings ``B`` on ``field_``'s edges, from ``R_guess``.

    Returns (the rotation or None when too few bearings stay in view or too few land on edges, bearings in view,
    of them on an edge).
    """
    shape = field_.dist.shape
    fx, fy = K[0, 0], K[1, 1]

    def cost(R):
        _, u, v, ok = _project(K, R, B, shape, cfg.border_px)
        a = np.abs(_bilinear(field_.dist, u[ok], v[ok]))
        a = np.concatenate([a, np.full(int((~ok).sum()), cfg.max_distance_px)])  # leaving the view is no way out
        return float(np.sum(np.where(a <= cfg.huber_px, 0.5 * a * a, cfg.huber_px * (a - 0.5 * cfg.huber_px))))

    R = np.asarray(R_guess, np.float64)
    c, lam = cost(R), 1e-3
    for _ in range(cfg.iterations):
        Xc, u, v, ok = _project(K, R, B, shape, cfg.border_px)
        if ok.sum() < cfg.min_edge_pixels:
            break
        Xc, u, v = Xc[ok], u[ok], v[ok]
        r = _bilinear(field_.dist, u, v)
        gu, gv = _bilinear(field_.gx, u, v), _bilinear(field_.gy, u, v)
        x, y, z = Xc[:, 0], Xc[:, 1], Xc[:, 2]
        g3 = np.stack([gu * fx / z, gv * fy / z, -(gu * fx * x + gv * fy * y) / z**2], axis=1)
        J = np.cross(Xc, g3)  # d r / d w for Xc -> exp(w) Xc
        a = np.abs(r)
        wts = np.where(a <= cfg.huber_px, 1.0, cfg.huber_px / np.maximum(a, 1e-12))
        H = (J * wts[:, None]).T @ J
        g = (J * wts[:, None]).T @ r
        improved = False
        for _ in range(6):  # Levenberg-Marquardt: the field's crest is a kink where plain Gauss-Newton overshoots
            try:
                w = -np.linalg.solve(H + lam * np.diag(np.diag(H) + 1e-12), g)
            except np.linalg.LinAlgError:
                return None, int(ok.sum()), 0
            R_new = R @ Rotation.from_rotvec(w).as_matrix().T  # camera points rotate by exp(w): R^T -> exp(w) R^T
            c_new = cost(R_new)
            if c_new < c:
                R, c, lam, improved = R_new, c_new, max(lam / 10.0, 1e-7), True
                break
            lam *= 10.0
        if not improved:
            break
    _, u, v, ok = _project(K, R, B, shape, cfg.border_px)
    n = int(ok.sum())
    n_in = int((_bilinear(field_.dist, u[ok], v[ok]) < cfg.inlier_px).sum()) if n else 0
    if n < cfg.min_edge_pixels or n_in < cfg.min_inlier_ratio * n:
        return None, n, n_in
    return R, n, n_in


def visual_rotation(prev8: np.ndarray, cur8: np.ndarray, K: np.ndarray, R_guess: np.ndarray,
                    cfg: VisualGyroConfig) -> np.ndarray | None:
    """Camera rotation ``R_prev_cur`` (3, 3) from the MCI ``prev8`` to the MCI ``cur8`` (None when not measured)."""
    field_ = edge_field(cur8, cfg)
    B = edge_bearings(prev8, K, cfg)
    if field_ is None or len(B) < cfg.min_edge_pixels:
        return None
    return align_rotation(field_, K, B, R_guess, cfg)[0]
