"""Brightness-edge contours inside one planar region: where the surface's albedo changes sharply.

A painted landing marker, a picture, a door or a screen a few centimetres proud of a wall
are no geometric edge the region growing can see, yet they fire the most events. Within
each fitted region:

1. the region's points (plane coordinates) and their intensities are rasterised at the
   point spacing and smoothed by normalised convolution (Gaussian-weighted mean of the
   points, so empty cells of a sparse scan and the region's rim add no gradient);
2. the gradient is expressed as the *contrast* of the step it implies (a step of height
   ``h`` blurred by ``sigma`` peaks at ``h / (sigma sqrt(2 pi))``), and OpenCV's Canny
   (non-maximum suppression + hysteresis on that contrast) marks thin edge curves; cells
   within ``1.5 sigma`` of the region's rim are ignored (points of the neighbouring face
   that joined the region along a crease would look like an albedo edge there);
3. the curves are linked into pixel chains, smoothed, resampled evenly, and each point is
   moved across the edge to where a least-squares step fitted to the raw points nearby
   puts it (robust to a mixture of two surfaces' points, e.g. a wall sampled behind a
   picture); straight runs are replaced by the step line fitted to all their points
   (:func:`step_fit.fit_step_lines`);
4. a chain is kept only if it is long enough, its median fitted step reaches the high
   threshold, and the intensities on its two sides differ by that much and by many
   standard errors (Welch t), so intensity noise alone leaves no contour.

Edge normals point from dark to bright; with ``brightness_sign = +1`` that is the
convention of :class:`evpose.core.contour_map.ContourMap` (gradient along
``brightness_sign * edge_normal``).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.albedo_corners import complete_corners
from evpose.mapping.edge_chains import _trace_chains
from evpose.mapping.marker_axis import fitted_lines, marker_axis
from evpose.mapping.panel_rims import join_panel_rims
from evpose.mapping.step_fit import fit_step_lines, local_steps, side_contrast, step_fit_points


_MAX_CELLS = 16_000_000
_NOISE_SAMPLES = 100_000
"""Most points the intensity-noise estimate of one region queries (an even stride beyond)."""
"""Largest raster per region; bigger regions get a coarser cell (bounds memory and time)."""
CORNER_MIN_ANGLE_DEG = 45.0
"""Two fitted lines of a chain meet at a corner (:func:`albedo_corners.complete_corners`) if their normals differ by at least this, degrees."""


@dataclass
class AlbedoContour:
    """Brightness-edge points of one region in its plane coordinates."""

    points2d: np.ndarray
    """Positions (a, b) along the region's in-plane axes, float64 (M, 2), metres."""
    normals2d: np.ndarray
    """Unit in-plane normals pointing from the darker to the brighter side, float64 (M, 2)."""
    contrast: np.ndarray
    """Fitted intensity step across the edge (bright minus dark), float64 (M,), intensity units."""


def _smooth_open(chain: np.ndarray, half: int) -> np.ndarray:
    if chain.shape[0] < 2 * half + 3 or half <= 0:
        return chain
    pad = np.concatenate([np.repeat(chain[:1], half, axis=0), chain, np.repeat(chain[-1:], half, axis=0)])
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    return np.stack([np.convolve(pad[:, d], kernel, mode="valid") for d in range(2)], axis=1)


def _resample_open(chain: np.ndarray, spacing: float) -> np.ndarray:
    seg = np.linalg.norm(np.diff(chain, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    length = s[-1]
    if length < 2 * spacing:
        return np.zeros((0, 2))
    n = int(round(length / spacing)) + 1
    t = np.linspace(0.0, length, n)
    return np.stack([np.interp(t, s, chain[:, d]) for d in range(2)], axis=1)


def _running_nanmedian(x: np.ndarray, half: int) -> np.ndarray:
    if half <= 0 or x.size == 0:
        return x
    pad = np.concatenate([np.full(half, np.nan), x, np.full(half, np.nan)])
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * half + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(win, axis=1)


def albedo_contours(
    own2d: np.ndarray,
    intensity: np.ndarray,
    spacing: float,
    sigma: float,
    high: float,
    low: float,
    min_length: float,
    contour_spacing: float,
    fit2d: np.ndarray | None = None,
    fit_intensity: np.ndarray | None = None,
    min_t: float = 6.0,
    axis_angle: float | None = None,
    axis_snap_deg: float = 0.0,
    fit_layer: np.ndarray | None = None,
    panel_snap_deg: float = 0.0,
    panel_gap: float = 0.0,
    corner_reach: float = 0.0,
    marker_snap_deg: float = 0.0,
) -> AlbedoContour:
    """Brightness-edge contour of one region (see the module docstring).

    ``own2d`` (N, 2) the region's points in plane coordinates, metres; ``intensity`` (N,)
    scaled to [0, 1]; ``spacing`` the raster cell
    (about the point spacing), ``sigma`` the smoothing scale, ``min_length`` the shortest
    chain kept, ``contour_spacing`` the output spacing, metres; ``high``/``low`` the
    hysteresis thresholds on the step contrast, intensity units; ``min_t`` the Welch t
    statistic the two sides of a kept chain must differ by (:func:`step_fit.side_contrast`). ``fit2d``/``fit_intensity``:
    the points the step fit localises edges with, if not the
    detection points themselves - all of a region's points, where detection used the front
    layer only: hiding the layer behind thins the bright side next to a proud object and
    would bias the fitted step outward, whereas a least-squares step between the
    mixture's mean and the plain side's is unbiased. ``axis_angle``/``axis_snap_deg``: straight
    runs nearly square to the region's outline are fitted square to it (:func:`step_fit.fit_step_lines`).
    ``fit_layer`` (per fit point: +1 front layer, -1 hidden behind it, 0 plain): runs along a
    proud panel's rim are placed by where the panel's points end, and squared to the outline
    within ``panel_snap_deg`` (:func:`step_fit.fit_step_lines`), the pieces of one rim placed
    together and continued across gaps up to ``panel_gap`` m to their corners
    (:func:`panel_rims.join_panel_rims`). ``corner_reach`` > 0: consecutive fitted lines of a chain
    meeting at a corner are continued to their crossing when it lies within this many metres of
    both (:func:`albedo_corners.complete_corners`); 0: off. ``marker_snap_deg`` > 0: the region's
    straight edges are first fitted freely, their common direction up to quarter turns taken as the
    region's marker axis (:func:`marker_axis.marker_axis`), and straight edges within this angle of
    it are then fitted square to it (a proud panel's rim keeps ``axis_angle`` and ``panel_snap_deg``;
    other edges take the marker's axis instead of ``axis_angle``/``axis_snap_deg``); 0: off.
    """
    if fit2d is None:
        fit2d, fit_intensity = own2d, intensity
    empty = AlbedoContour(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
    if own2d.shape[0] < 20 or not np.ptp(intensity) > low:
        return empty
    lo = own2d.min(axis=0)
    extent = own2d.max(axis=0) - lo
    cell = spacing
    if (extent[0] / cell + 1) * (extent[1] / cell + 1) > _MAX_CELLS:
        cell = float(np.sqrt(extent[0] * extent[1] / _MAX_CELLS)) * 1.01
    sig_cells = max(sigma / cell, 0.7)
    margin = int(math.ceil(6 * sig_cells)) + 2
    w = int(np.floor(extent[0] / cell + 0.5)) + 1 + 2 * margin
    h = int(np.floor(extent[1] / cell + 0.5)) + 1 + 2 * margin
    ij = np.floor((own2d - lo) / cell + 0.5).astype(np.int64) + margin
    flat = ij[:, 1] * w + ij[:, 0]
    count = np.bincount(flat, minlength=h * w).reshape(h, w).astype(np.float32)
    total = np.bincount(flat, weights=intensity, minlength=h * w).reshape(h, w).astype(np.float32)
    ksize = 2 * int(math.ceil(3 * sig_cells)) + 1
    wc = cv2.GaussianBlur(count, (ksize, ksize), sig_cells, borderType=cv2.BORDER_CONSTANT)
    ws = cv2.GaussianBlur(total, (ksize, ksize), sig_cells, borderType=cv2.BORDER_CONSTANT)
    # The region's extent from the point density at twice the scale: at the smoothing scale
    # itself a sparse random scan's density fluctuates by half, which would riddle it with holes.
    big = 2.0 * sig_cells
    kbig = 2 * int(math.ceil(3 * big)) + 1
    density = cv2.GaussianBlur(count, (kbig, kbig), big, borderType=cv2.BORDER_CONSTANT)
    typical = float(np.median(density[count > 0]))
    inside = (density >= 0.5 * typical).astype(np.uint8)
    # Ignore the rim: crease points of the neighbouring face (and the smoothing's own edge) live there.
    rim = int(math.ceil(1.5 * sig_cells))
    inside = cv2.erode(inside, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * rim + 1, 2 * rim + 1)))
    if not inside.any():
        return empty
    img = np.where(wc > 1e-6, ws / np.maximum(wc, 1e-6), 0.0).astype(np.float32)
    # Central differences (Sobel of aperture 3 divided by 8) in intensity per cell, times the
    # blurred-step peak factor: the gradient read as the height of the step it implies.
    to_contrast = sig_cells * math.sqrt(2.0 * math.pi) / 8.0
    gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3) * to_contrast
    gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3) * to_contrast
    gx[inside == 0] = 0.0
    gy[inside == 0] = 0.0
    scale = 1000.0  # contrast units -> int16 for cv2.Canny's custom-gradient form
    dx16 = np.clip(np.rint(gx * scale), -32767, 32767).astype(np.int16)
    dy16 = np.clip(np.rint(gy * scale), -32767, 32767).astype(np.int16)
    edges = cv2.Canny(dx16, dy16, low * scale, high * scale, L2gradient=True)
    edges[inside == 0] = 0
    if not edges.any():
        return empty
    # Noisy intensities need a larger step: at least 2.5 times the point-to-point noise,
    # estimated from nearest-neighbour differences (robust: most pairs share one albedo).
    # A median needs no million samples: an even stride over a large region (a ground plane)
    # gives the same figure for a fraction of the nearest-neighbour queries.
    stride = max(1, own2d.shape[0] // _NOISE_SAMPLES)
    det_tree = cKDTree(own2d)
    _, j_nn = det_tree.query(own2d[::stride], k=2)
    noise = float(np.median(np.abs(intensity[::stride] - intensity[j_nn[:, 1]]))) / (math.sqrt(2.0) * 0.6745)
    min_step = max(high, 2.5 * noise)
    rows, cols, starts = _trace_chains((edges > 0).astype(np.uint8))
    # KD-trees only once there is something to fit (most regions of a scan have no albedo edge).
    own_tree = det_tree if fit2d is own2d else cKDTree(fit2d)
    min_pix = max(3, int(math.ceil(min_length / cell)))
    half_across = max(2.5 * spacing, 1.2 * sigma)
    half_along = max(3.0 * spacing, 1.5 * sigma)
    def trace(marker_angle, lines_out=None):
        pts_out, nrm_out, con_out = [], [], []
        for c in range(starts.size - 1):
            a, b = starts[c], starts[c + 1]
            if b - a < min_pix:
                continue
            chain = (np.stack([cols[a:b], rows[a:b]], axis=1).astype(np.float64) - margin) * cell + lo
            chain = _smooth_open(chain, 2)
            p = _resample_open(chain, contour_spacing)
            if p.shape[0] < 3:
                continue
            span = max(1, int(round(cell / contour_spacing)))
            idx = np.arange(p.shape[0])
            tangent = p[np.minimum(idx + span, idx[-1])] - p[np.maximum(idx - span, 0)]
            tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
            normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
            pix = np.clip(np.floor((p - lo) / cell + 0.5).astype(np.int64) + margin, 0, [w - 1, h - 1])
            g = np.stack([gx[pix[:, 1], pix[:, 0]], gy[pix[:, 1], pix[:, 0]]], axis=1)
            flip = np.einsum("md,md->m", normal, g) < 0
            normal[flip] *= -1.0
            k = int(min(fit2d.shape[0], max(16, 4 * math.ceil(half_across * half_along / (spacing * spacing)))))
            dist, nb = own_tree.query(p, k=k, distance_upper_bound=math.hypot(half_across, half_along))
            nb = np.asarray(nb, np.int64).reshape(p.shape[0], -1)
            n_nb = np.isfinite(np.asarray(dist).reshape(p.shape[0], -1)).sum(axis=1)
            offset, step = step_fit_points(p, normal, tangent, fit2d, fit_intensity, nb, n_nb, half_across, half_along, 2)
            # The fitted step must rise along the normal (bright side where the gradient said).
            offset[~(step > 0)] = np.nan
            step = np.where(step > 0, step, np.nan)
            smooth = max(2, int(round(1.5 * spacing / contour_spacing)))
            offset = _running_nanmedian(offset, smooth)
            good = np.isfinite(offset)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                chain_step = float(np.nanmedian(step)) if np.isfinite(step).any() else 0.0
            if good.sum() < 3 or not chain_step >= high:
                continue
            p = p[good] + np.clip(offset[good], -half_across, half_across)[:, None] * normal[good]
            nrm = normal[good]
            # Man-made albedo edges are mostly straight: fit lines to straight runs (averages the scatter).
            # Twice: runs split by the raw chain's jaggedness are collinear after the first fit and merge.
            fitted = np.zeros(p.shape[0], bool)
            for _ in range(2):
                p, nrm, on_line = fit_step_lines(p, nrm, fit2d, fit_intensity, own_tree, eps=2.0 * spacing,
                                           min_points=max(8, int(round(4 * spacing / contour_spacing))),
                                           half_across=half_across, width=0.5 * spacing,
                                           axis_angle=axis_angle, axis_snap_deg=axis_snap_deg, fit_layer=fit_layer,
                                           panel_snap_deg=panel_snap_deg, marker_angle=marker_angle,
                                           marker_snap_deg=marker_snap_deg)
                fitted |= on_line
            chain_lines = fitted_lines(p, nrm, on_line) if lines_out is not None else []
            if corner_reach > 0:
                p, nrm = complete_corners(p, nrm, fitted, contour_spacing, CORNER_MIN_ANGLE_DEG, corner_reach,
                                          max(8, int(round(4 * spacing / contour_spacing))))
            # Keep only the stretches that still separate two brightness levels (a chain can run
            # from a real edge into a patch of noise or of two mixed layers).
            # (A window of ~15 point spacings along the chain holds ~8 points on either side.)
            local = local_steps(p, nrm, fit2d, fit_intensity, own_tree, half_across, 0.2 * spacing,
                                max(2, int(round(7.0 * spacing / contour_spacing))))
            keep = ~(local < min_step)  # NaN (too few points to tell) keeps the point
            if keep.sum() < 3:
                continue
            p, nrm = p[keep], nrm[keep]
            step_all, t_stat = side_contrast(p, nrm, fit2d, fit_intensity, own_tree, half_across, 0.2 * spacing)
            if not (step_all >= min_step and t_stat >= min_t):
                continue
            if lines_out is not None:
                lines_out.extend(chain_lines)
            pts_out.append(p)
            nrm_out.append(nrm)
            con_out.append(np.full(p.shape[0], step_all))
        return pts_out, nrm_out, con_out

    if marker_snap_deg > 0:
        # A marker's straight edges share one direction up to quarter turns: found from every
        # freely fitted line of the region at once, then each line is fitted square to it.
        found: list = []
        trace(None, found)
        marker = marker_axis(found)
    else:
        marker = None
    pts_out, nrm_out, con_out = trace(marker)
    if not pts_out:
        return empty
    p, nrm, con = np.concatenate(pts_out), np.concatenate(nrm_out), np.concatenate(con_out)
    if fit_layer is not None:
        p, nrm = join_panel_rims(p, nrm, fit2d, fit_intensity, fit_layer, own_tree, half_across,
                                 max_gap=panel_gap, spacing=contour_spacing)
        con = np.concatenate([con, np.full(p.shape[0] - con.size, float(np.median(con)))])
    return AlbedoContour(p, nrm, con)


def region_albedo_edges(
    points: np.ndarray,
    intensity: np.ndarray,
    region_points: list[np.ndarray],
    visible: np.ndarray,
    centroids: np.ndarray,
    axes: np.ndarray,
    spacing: float,
    sigma: float,
    high: float,
    low: float,
    min_length: float,
    contour_spacing: float,
    min_t: float = 6.0,
    axis_angles: np.ndarray | None = None,
    axis_snap_deg: float = 0.0,
    plane_normals: np.ndarray | None = None,
    layer_m: float = 0.0,
    panel_snap_deg: float = 0.0,
    panel_gap: float = 0.0,
    corner_reach: float = 0.0,
    marker_snap_deg: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Brightness-edge contour points of every region, in the world.

    ``region_points[r]``: indices of region r's points; ``visible`` (N,) bool: points on the
    front layer (:func:`evpose.mapping.visibility.front_layer`), the only ones whose
    intensity the detection uses; ``centroids``/``axes`` the regions' planes; ``intensity``
    (N,) in [0, 1] (colours, albedo) or any other unit, then scaled to [0, 1] over the whole
    cloud (so the thresholds mean the same for every region). ``axis_angles`` (R,): each
    region's outline direction in its plane coordinates, radians (NaN: none), to which
    straight edges within ``axis_snap_deg`` are squared. ``plane_normals`` (R, 3, facing the
    viewer) and ``layer_m`` > 0: points more than ``layer_m`` in front of their region's plane are
    its front layer, and edges along the rim of such a layer are placed by where its points
    end and squared to the outline within ``panel_snap_deg`` (:func:`step_fit.fit_step_lines`),
    and continued across gaps up to ``panel_gap`` m to their corners (:func:`panel_rims.join_panel_rims`);
    None or 0: off. ``corner_reach``, ``marker_snap_deg``: see :func:`albedo_contours`. Returns points (M, 3), unit
    edge normals (M, 3) pointing dark -> bright, region ids (M,) int32.
    """
    lo_i, hi_i = float(np.min(intensity)), float(np.max(intensity))
    out_p, out_n, out_r = [], [], []
    if hi_i > lo_i:
        # Colours and albedos are already in [0, 1] and keep their meaning; only other units
        # (raw LiDAR intensity) are scaled. Stretching a nearly uniform cloud's own range to
        # [0, 1] would turn its noise into contrast.
        inten = intensity if lo_i >= 0.0 and hi_i <= 1.0 else (intensity - lo_i) / (hi_i - lo_i)
        for r, all_idx in enumerate(region_points):
            idx = all_idx[visible[all_idx]]
            vals = inten[idx]
            if idx.size < 20 or not np.ptp(vals) > low:
                continue
            c, ax = centroids[r], axes[r]
            rel = points[idx] - c
            own2d = np.stack([rel @ ax[0], rel @ ax[1]], axis=1)
            rel = points[all_idx] - c
            all2d = np.stack([rel @ ax[0], rel @ ax[1]], axis=1)
            layer = None
            if plane_normals is not None and layer_m > 0:
                # Offsets from the region's plane, which the wall's many points pin: a panel's
                # front stands out by its thickness, a plain plane's noise rarely by layer_m.
                layer = np.where(rel @ plane_normals[r] > layer_m, 1, np.where(visible[all_idx], 0, -1)).astype(np.int8)
            ac = albedo_contours(own2d, vals, spacing, sigma, high, low, min_length, contour_spacing,
                                 all2d, inten[all_idx], min_t,
                                 None if axis_angles is None or not np.isfinite(axis_angles[r]) else float(axis_angles[r]),
                                 axis_snap_deg, layer, panel_snap_deg, panel_gap, corner_reach,
                                 marker_snap_deg)
            if ac.points2d.shape[0] == 0:
                continue
            out_p.append(c + ac.points2d[:, :1] * ax[0] + ac.points2d[:, 1:] * ax[1])
            out_n.append(ac.normals2d[:, :1] * ax[0] + ac.normals2d[:, 1:] * ax[1])
            out_r.append(np.full(ac.points2d.shape[0], r, np.int32))
    if not out_p:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int32)
    return np.concatenate(out_p), np.concatenate(out_n), np.concatenate(out_r)
