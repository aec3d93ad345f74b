"""Where exactly an albedo edge lies: least-squares intensity steps fitted to the raw points.

Per edge point (:func:`step_fit_points`), per straight run of an edge chain
(:func:`fit_step_lines`), and a whole chain's significance (:func:`side_contrast`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from evpose.mapping.panel_rims import panel_edge_shift, panel_side


@numba.njit(cache=True)
def step_fit_points(pts, normals, tangents, own, inten, nb_idx, nb_count, half_across, half_along, min_side):
    """Least-squares step across each edge point: the offset along its normal and the step height.

    For point i the region points within ``half_along`` along the edge and ``half_across``
    across it are sorted by their offset d along the normal; the split between consecutive
    offsets that minimises the two sides' squared deviations from their means is the edge.
    Returns (offset (M,), step (M,) = mean after - mean before); NaN where too few points.
    """
    m = pts.shape[0]
    offset = np.full(m, np.nan)
    step = np.full(m, np.nan)
    dvals = np.empty(nb_idx.shape[1])
    ivals = np.empty(nb_idx.shape[1])
    for i in range(m):
        n = 0
        for jj in range(nb_count[i]):
            j = nb_idx[i, jj]
            rx = own[j, 0] - pts[i, 0]
            ry = own[j, 1] - pts[i, 1]
            d = rx * normals[i, 0] + ry * normals[i, 1]
            t = rx * tangents[i, 0] + ry * tangents[i, 1]
            if abs(d) <= half_across and abs(t) <= half_along:
                dvals[n] = d
                ivals[n] = inten[j]
                n += 1
        if n < 2 * min_side:
            continue
        order = np.argsort(dvals[:n], kind="mergesort")
        d_s = dvals[:n][order]
        i_s = ivals[:n][order]
        total = 0.0
        total2 = 0.0
        for k in range(n):
            total += i_s[k]
            total2 += i_s[k] * i_s[k]
        left = 0.0
        best = -1.0
        best_k = -1
        for k in range(n - 1):
            left += i_s[k]
            nl = k + 1
            nr = n - nl
            if nl < min_side or nr < min_side:
                continue
            # SSE = total2 - left^2/nl - right^2/nr: maximise the explained part.
            right = total - left
            score = left * left / nl + right * right / nr
            if score > best:
                best = score
                best_k = k
        if best_k < 0:
            continue
        nl = best_k + 1
        left = 0.0
        for k in range(nl):
            left += i_s[k]
        offset[i] = 0.5 * (d_s[best_k] + d_s[best_k + 1])
        step[i] = (total - left) / (n - nl) - left / nl
    return offset, step


def _soft_step_fit(d: np.ndarray, vals: np.ndarray, offsets: np.ndarray, width: float) -> tuple[float, float, float, float]:
    """Best soft step ``lo + (hi - lo) * Phi((d - o) / width)`` over the candidate offsets ``o``.

    Returns (residual sum of squares, offset, step ``hi - lo``, ``lo``). A blurred step rather than a
    hard split: on a sparse scan many splits separate the two sides equally well, and the
    blurred step's least squares puts the edge in the middle of the gap between them.
    """
    from scipy.special import ndtr

    phi = ndtr((d[:, None] - offsets[None, :]) / width)  # (n, K)
    n = float(d.size)
    s1 = phi.sum(axis=0)
    s2 = (phi * phi).sum(axis=0)
    sy = float(vals.sum())
    sxy = vals @ phi
    det = n * s2 - s1 * s1
    ok = det > 1e-9
    det = np.where(ok, det, 1.0)
    lo = (s2 * sy - s1 * sxy) / det
    step = (n * sxy - s1 * sy) / det
    sse = float(vals @ vals) - (lo * sy + step * sxy)
    sse = np.where(ok, sse, np.inf)
    k = int(np.argmin(sse))
    return float(sse[k]), float(offsets[k]), float(step[k]), float(lo[k])


def _margin_line(rel: np.ndarray, vals: np.ndarray, n: np.ndarray, off: float, mid: float,
                 max_turn_deg: float = 8.0, outliers: float = 0.05) -> tuple[np.ndarray, float] | None:
    """The widest-margin line between the dark and the bright points: (normal, offset), or None.

    The points are labelled bright or dark at the mid-level ``mid``. For normals within
    ``max_turn_deg`` of ``n`` the margin is the gap between the bright side's lowest and the
    dark side's highest projection (ignoring the ``outliers`` fraction of each side: a
    second layer or noise); the widest gap wins and the edge is its middle. A step fit's
    cost hardly changes while the line turns inside that gap, so on a sparse scan the
    widest gap pins the tilt far better. Only for two clean sides: if more than twice
    ``outliers`` of the points lie on the wrong side of the step line ``rel . n = off`` (a
    mixture of two layers, heavy noise) the margin means nothing and None is returned.
    """
    bright = vals > mid
    if np.mean((rel @ n > off) != bright) > 2.0 * outliers:
        return None
    nb, nd = int(bright.sum()), int((~bright).sum())
    if nb < 3 or nd < 3:
        return None
    turns = np.radians(np.arange(-max_turn_deg, max_turn_deg + 1e-9, 0.1))
    normals = np.stack([np.cos(turns) * n[0] - np.sin(turns) * n[1], np.sin(turns) * n[0] + np.cos(turns) * n[1]], axis=1)
    proj = rel @ normals.T  # (points, turns)
    kb, kd = int(outliers * nb), int(outliers * nd)
    low_bright = np.sort(proj[bright], axis=0)[kb]
    high_dark = -np.sort(-proj[~bright], axis=0)[kd]
    margin = low_bright - high_dark
    k = int(np.argmax(margin))
    # Ties (several turns with the same gap) resolve to their middle: the most central line.
    ties = np.flatnonzero(margin >= margin[k] - 1e-12)
    k = int(ties[ties.size // 2])
    return normals[k], 0.5 * float(low_bright[k] + high_dark[k])


def fit_step_lines(p: np.ndarray, normals: np.ndarray, fit2d: np.ndarray, fit_intensity: np.ndarray, tree,
                   eps: float, min_points: int, half_across: float, width: float,
                   min_band_points: int = 8, max_tilt_deg: float = 12.0, n_tilts: int = 25,
                   axis_angle: float | None = None, axis_snap_deg: float = 0.0,
                   fit_layer: np.ndarray | None = None, panel_snap_deg: float = 0.0,
                   marker_angle: float | None = None, marker_snap_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Replace straight runs of an open edge chain by the step line fitted to all raw points along them.

    Per-point step fits on a sparse, mixed scan scatter by centimetres; a straight painted
    edge is better found once from every point along it. The chain is split into straight
    runs (Douglas-Peucker, ``eps``); for each run of at least ``min_points`` points, the
    region's points within ``half_across`` of the run's line and along its extent are projected
    onto the normals of lines tilted by up to ``max_tilt_deg`` about the run's centre, and
    the tilt and offset of the blurred step (``width`` m, :func:`_soft_step_fit`) with the
    least squared residual win. Points of the run are projected onto that line and take its normal (still dark ->
    bright). Runs with fewer than ``min_band_points`` points in their band, or where the step
    does not rise along the normal, are left as they are.
    ``axis_angle`` (radians, modulo 90 degrees): the direction of the region's own outline
    (:func:`dominant_axis`); a run whose normal lies within ``axis_snap_deg`` of it or of its
    perpendicular is fitted at exactly that direction, only its offset free. On a 10 cm
    scan a line's tilt rests on the few points nearest its ends and comes out several
    degrees off (centimetres at a panel's corners), while a door, picture or painted
    marker is nearly always square to the wall or pad it lies on.
    ``fit_layer`` (N,) int8 per fit point: +1 in front of its region's plane, -1 hidden behind
    such a front, 0 plain; with it, a run along a proud panel's rim is placed by where the
    panel's own points end (:func:`panel_rims.panel_edge_shift`), not by the step fit, and squared to
    ``axis_angle`` within ``panel_snap_deg`` (a door or picture is square to its wall; a
    painted marker, on one layer, keeps ``axis_snap_deg``). None: off.
    ``marker_angle`` (radians, modulo 90 degrees): the direction the region's painted marker is
    square to (:func:`marker_axis.marker_axis`); runs that are no proud panel's rim and lie within
    ``marker_snap_deg`` of it or its perpendicular are fitted at exactly that direction. None: off.
    Returns the points, their normals and a mask (M,) of the points on a fitted line.
    """
    from evpose.mapping.contours import _dp_indices

    m = p.shape[0]
    fitted = np.zeros(m, bool)
    if m < min_points:
        return p, normals, fitted
    far = int(np.argmax(np.hypot(*(p - p[0]).T)))
    cuts = [0, far, m - 1]
    _dp_indices(p, 0, far, eps, cuts)
    _dp_indices(p, far, m - 1, eps, cuts)
    cuts = sorted({m if c == m - 1 else c for c in cuts})
    out_p, out_n = p.copy(), normals.copy()
    tilts = np.radians(np.linspace(-max_tilt_deg, max_tilt_deg, n_tilts))
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a < min_points:
            continue
        run = p[a:b]
        c = run.mean(axis=0)
        _, _, vt = np.linalg.svd(run - c, full_matrices=False)
        direction = vt[0]
        n0 = np.array([-direction[1], direction[0]])
        if n0 @ normals[a:b].sum(axis=0) < 0:
            n0 = -n0
        t_run = (run - c) @ direction
        t_lo, t_hi = float(t_run.min()), float(t_run.max())
        # The band spans the run's own extent, untrimmed. The traced chain already stops short
        # of corners (smoothing rounds them, Douglas-Peucker cuts there), and on a sparse scan
        # the few points nearest the edge decide where it is: trimming the ends by the band's
        # width (as before) dropped them: the landing pad's painted edges (10 cm point spacing) were
        # 17 mm off (median), 9.5 mm with the whole run.
        cand = np.asarray(tree.query_ball_point(c, math.hypot(max(-t_lo, t_hi), 1.5 * half_across)), np.int64)
        if cand.size < 2 * min_points // 4:
            continue
        rel = fit2d[cand] - c
        t_rel = rel @ direction
        band = (t_rel >= t_lo) & (t_rel <= t_hi) & (np.abs(rel @ n0) <= half_across)
        rel, vals = rel[band], fit_intensity[cand[band]]
        lay = None if fit_layer is None else fit_layer[cand[band]]
        if vals.size < min_band_points:
            continue
        # Decided before the tilt search, about the run's own line: only a panel's rim is squared.
        snap_deg, angle = axis_snap_deg, axis_angle
        if lay is not None and panel_snap_deg > axis_snap_deg and panel_side(rel @ n0, lay) != 0.0:
            snap_deg = panel_snap_deg
        elif marker_angle is not None and marker_snap_deg > 0:
            snap_deg, angle = marker_snap_deg, marker_angle
        run_tilts, fine_turns, margin_turn = tilts, np.radians(np.arange(-1.5, 1.5001, 0.1)), 8.0
        if angle is not None and snap_deg > 0:
            to_axis = (angle - math.atan2(n0[1], n0[0]) + 0.25 * math.pi) % (0.5 * math.pi) - 0.25 * math.pi
            if abs(to_axis) <= math.radians(snap_deg):
                run_tilts, fine_turns, margin_turn = np.array([to_axis]), np.zeros(1), 0.0
        # Coarse: a blurred step of the point spacing over all tilts; fine: a sharp step around
        # the best, which puts the line in the middle of the gap between the two sides' points.
        best = (np.inf, 0.0, 0.0, n0, 0.0)
        stages = ((run_tilts, np.arange(-half_across, half_across + 1e-9, 0.1 * width), width), None)
        for stage in stages:
            if stage is None:
                fine = 0.25 * width
                stage = (best[4] + fine_turns,
                         best[1] + np.arange(-width, width + 1e-9, 0.1 * fine), fine)
            grid, offsets, w_step = stage
            best = (np.inf, best[1], best[2], best[3], best[4], 0.0)
            for tilt in grid:
                ct, st = math.cos(tilt), math.sin(tilt)
                n = np.array([ct * n0[0] - st * n0[1], st * n0[0] + ct * n0[1]])
                sse, off, step, lo = _soft_step_fit(rel @ n, vals, offsets, w_step)
                if sse < best[0]:
                    best = (sse, off, step, n, tilt, lo)
        sse, off, step, n, _, lo = best
        if not (np.isfinite(sse) and step > 0):
            continue
        shift = None if lay is None else panel_edge_shift(rel @ n - off, vals, lay, -half_across - off,
                                                            half_across - off, lo + 0.5 * step)
        if shift is not None:
            off += shift
        else:
            line = _margin_line(rel, vals, n, off, lo + 0.5 * step, max_turn_deg=margin_turn)
            if line is not None:
                n, off = line
        d = np.array([n[1], -n[0]])
        base = c + off * n
        out_p[a:b] = base + ((run - base) @ d)[:, None] * d
        out_n[a:b] = n
        fitted[a:b] = True
    return out_p, out_n, fitted


def dominant_axis(normals2d: np.ndarray, min_coherence: float = 0.5) -> float | None:
    """The direction (radians, modulo 90 degrees) most of these 2D normals share up to quarter turns, or None.

    The mean of ``exp(4i theta)`` over the normals: a rectangular outline's four sides add
    up, a round one's cancel. None when its length is under ``min_coherence`` (no square
    outline) or there are no normals.
    """
    nrm = np.asarray(normals2d, np.float64).reshape(-1, 2)
    if nrm.shape[0] == 0:
        return None
    z = np.exp(4j * np.arctan2(nrm[:, 1], nrm[:, 0])).mean()
    if abs(z) < min_coherence:
        return None
    return float(np.angle(z)) / 4.0


def side_contrast(p: np.ndarray, normals: np.ndarray, fit2d: np.ndarray, fit_intensity: np.ndarray, tree,
                   half_across: float, dead: float) -> tuple[float, float]:
    """Intensity step across a whole chain and its Welch t statistic.

    Every point within ``half_across`` of the chain (and more than ``dead`` off it) is put on
    the bright or dark side of its nearest chain point; the step is the difference of the
    two sides' means. Canny follows the strongest gradients of the smoothed image, so a
    chain traced through plain intensity noise has sides that differ a little; they differ
    by many standard errors only across a real edge.
    """
    from scipy.spatial import cKDTree

    cand = np.unique(np.concatenate(tree.query_ball_point(p, half_across)).astype(np.int64)) if p.shape[0] else np.zeros(0, np.int64)
    if cand.size < 6:
        return 0.0, 0.0
    dist, j = cKDTree(p).query(fit2d[cand], k=1)
    d = np.einsum("md,md->m", fit2d[cand] - p[j], normals[j])
    # Mostly across the edge (not beyond the chain's ends).
    across = np.abs(d) >= 0.7 * dist
    hi = fit_intensity[cand[across & (d > dead)]]
    lo = fit_intensity[cand[across & (d < -dead)]]
    if hi.size < 3 or lo.size < 3:
        return 0.0, 0.0
    step = float(hi.mean() - lo.mean())
    se = math.sqrt(hi.var(ddof=1) / hi.size + lo.var(ddof=1) / lo.size)
    return step, step / max(se, 1e-6)


def local_steps(p: np.ndarray, normals: np.ndarray, fit2d: np.ndarray, fit_intensity: np.ndarray, tree,
                half_across: float, dead: float, half_window: int) -> np.ndarray:
    """Intensity step across an ordered chain at each of its points, over ``2 * half_window + 1`` chain points.

    As :func:`side_contrast`, but summed over a sliding window along the chain: where a
    chain wanders off a real edge into a patch of noise or a mixture of two layers, the
    two sides stop differing there. NaN where either side has fewer than 3 points.
    """
    from scipy.spatial import cKDTree

    m = p.shape[0]
    out = np.full(m, np.nan)
    if m == 0:
        return out
    cand = np.unique(np.concatenate(tree.query_ball_point(p, half_across)).astype(np.int64))
    if cand.size == 0:
        return out
    dist, j = cKDTree(p).query(fit2d[cand], k=1)
    d = np.einsum("md,md->m", fit2d[cand] - p[j], normals[j])
    across = np.abs(d) >= 0.7 * dist
    vals = fit_intensity[cand]
    sums = []
    for side in (across & (d > dead), across & (d < -dead)):
        s = np.bincount(j[side], weights=vals[side], minlength=m)
        c = np.bincount(j[side], minlength=m).astype(np.float64)
        cs, cc = np.concatenate([[0.0], np.cumsum(s)]), np.concatenate([[0.0], np.cumsum(c)])
        lo_i = np.clip(np.arange(m) - half_window, 0, m)
        hi_i = np.clip(np.arange(m) + half_window + 1, 0, m)
        sums.append((cs[hi_i] - cs[lo_i], cc[hi_i] - cc[lo_i]))
    (s_hi, n_hi), (s_lo, n_lo) = sums
    ok = (n_hi >= 3) & (n_lo >= 3)
    out[ok] = s_hi[ok] / n_hi[ok] - s_lo[ok] / n_lo[ok]
    return out
