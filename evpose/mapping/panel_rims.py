"""Brightness edges along the rim of a panel proud of its wall: placed by where the panel's own points end.

A door, picture or screen a couple of centimetres in front of a wall is traced as a brightness
edge of the wall's region (its front and the wall behind it fall into one region). Its sides
are not alike: inside the outline the panel's front lies over the wall sampled behind it, the
panel's thin side faces leak its intensity a range-noise sigma beyond the rim, and outside
there is the wall alone; an intensity step fit centres the edge in the gap between the last
panel-coloured point and the first wall point beyond it, 1-2 cm outward on a 10 cm scan.
The panel's own points (its intensity, in front of the wall or hidden behind that front)
exist only inside the outline: where they end is the rim (:func:`panel_edge_offset`), the
more of the rim's length they are gathered along the better (:func:`join_panel_rims`).
"""

from __future__ import annotations

import numpy as np

_RANK = 2


def panel_side(u: np.ndarray, layer: np.ndarray, min_front: int = 4, min_front_frac: float = 0.15,
                max_other_frac: float = 0.3) -> float:
    """Which side of a line a proud panel lies on: +1 / -1 along the line's normal, 0 if neither.

    ``u`` (n,) the band's points' signed distances from the line, ``layer`` (n,) +1 for points
    in front of their region's plane (-1 hidden behind such a front, 0 plain). A panel side
    holds at least ``min_front`` and ``min_front_frac`` front points, the other side under
    ``max_other_frac`` of that fraction (a plain noisy plane has ~1 % on both sides).
    """
    front = layer > 0
    pos, neg = u > 0, u < 0
    n_pos, n_neg = int(np.sum(front & pos)), int(np.sum(front & neg))
    f_pos = n_pos / max(int(pos.sum()), 1)
    f_neg = n_neg / max(int(neg.sum()), 1)
    s = 1.0 if f_pos >= f_neg else -1.0
    n_panel, f_panel, f_other = (n_pos, f_pos, f_neg) if s > 0 else (n_neg, f_neg, f_pos)
    if n_panel < min_front or f_panel < min_front_frac or f_other > max_other_frac * f_panel:
        return 0.0
    return s


def panel_edge_shift(u: np.ndarray, vals: np.ndarray, layer: np.ndarray, u_lo: float, u_hi: float,
                     mid: float | None = None, min_points: int = 6) -> float | None:
    """How far to move a line along its normal onto a proud panel's rim; None where no panel is in view.

    ``u`` (n,) signed distances of the band's points from the line (the band spans ``u_lo`` to
    ``u_hi``), ``vals`` their intensities, ``layer`` as in :func:`panel_side`; ``mid`` the level
    between the panel's and the wall's intensity (None: between the panel's front points' median
    and the other side's). The panel's points (its side's intensity, ``layer`` != 0) are uniform
    inside the outline with density ``lam`` along the normal, so the second outermost lies 2/lam
    inside the rim on average (the second: one side-face or misclassified point is ignored);
    ``lam`` is counted over the band's reach into the panel behind that point.
    """
    s = panel_side(u, layer)
    if s == 0.0:
        return None
    inner = (u > 0) if s > 0 else (u < 0)
    if mid is None:
        if not (~inner).any():
            return None
        mid = 0.5 * float(np.median(vals[inner & (layer > 0)]) + np.median(vals[~inner]))
    panel_like = (vals > mid) if s > 0 else (vals < mid)
    out = np.sort(-s * u[panel_like & (layer != 0)])[::-1]  # outward from the panel, largest first
    if out.size < min_points:
        return None
    k = _RANK
    window = 0.8 * ((u_hi if s > 0 else -u_lo) + out[k - 1])  # from the k-th outermost into the panel
    behind = int(np.sum((out < out[k - 1]) & (out >= out[k - 1] - window)))
    if behind < min_points - 2:
        return None
    return -s * float(out[k - 1] + k * window / behind)


def join_panel_rims(p: np.ndarray, normals: np.ndarray, fit2d: np.ndarray, fit_intensity: np.ndarray,
                    fit_layer: np.ndarray, tree, half_across: float, max_turn_deg: float = 0.5,
                    max_offset: float = 0.03, min_points: int = 10, max_gap: float = 0.0,
                    spacing: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Brightness-edge points of one region, the pieces of each straight panel rim placed together.

    A door's side is often traced as several chains, each placed by the few panel points beside
    it (the rim's error is about one point gap across: the shorter the piece, the larger).
    Points whose normals agree within ``max_turn_deg`` (squared rims agree exactly) and whose
    lines lie within ``max_offset`` of each other are one rim, placed once by the panel points
    along all of it (:func:`panel_edge_shift` over the band ``half_across`` either side of the
    rim's mean line and within its extent) and given the same normal. Pieces with no panel
    beside them, or under ``min_points`` points, stay as they are. ``p``/``normals`` (M, 2),
    ``fit2d``/``fit_intensity``/``fit_layer`` the region's points. With ``max_gap`` > 0 placed
    rims are continued up to their square neighbours' lines (:func:`_complete_corners`, points
    ``spacing`` apart, appended at the end). Returns the points and normals, the appended
    ones last.
    """
    p, normals = p.copy(), normals.copy()
    rims = []
    m = p.shape[0]
    if m < min_points:
        return p, normals
    theta = np.arctan2(normals[:, 1], normals[:, 0])
    order = np.argsort(theta, kind="stable")
    tol = np.radians(max_turn_deg)
    # Angle clusters (a gap of more than tol between sorted angles splits them), the seam at +-pi closed.
    cut = np.flatnonzero(np.diff(theta[order]) > tol) + 1
    groups = np.split(order, cut)
    if len(groups) > 1 and theta[order[0]] + 2 * np.pi - theta[order[-1]] <= tol:
        groups = [np.concatenate([groups[-1], groups[0]])] + groups[1:-1]
    for g in groups:
        if g.size < min_points:
            continue
        n = normals[g].sum(axis=0)
        n /= max(np.linalg.norm(n), 1e-12)
        off = p[g] @ n
        o_order = np.argsort(off, kind="stable")
        for sub in np.split(g[o_order], np.flatnonzero(np.diff(off[o_order]) > max_offset) + 1):
            if sub.size < min_points:
                continue
            d = np.array([n[1], -n[0]])
            o = float(np.mean(p[sub] @ n))
            t = p[sub] @ d
            t_lo, t_hi = float(t.min()), float(t.max())
            centre = 0.5 * (t_lo + t_hi) * d + o * n
            cand = np.asarray(tree.query_ball_point(centre, float(np.hypot(0.5 * (t_hi - t_lo), half_across))), np.int64)
            if cand.size == 0:
                continue
            rel = fit2d[cand]
            u = rel @ n - o
            tt = rel @ d
            band = (np.abs(u) <= half_across) & (tt >= t_lo) & (tt <= t_hi)
            shift = panel_edge_shift(u[band], fit_intensity[cand[band]], fit_layer[cand[band]], -half_across, half_across)
            if shift is None:
                continue
            p[sub] += (o + shift - p[sub] @ n)[:, None] * n
            normals[sub] = n
            rims.append((n, d, o + shift, t_lo, t_hi))
    extra_p, extra_n = _complete_corners(rims, fit2d, fit_layer, tree, half_across, max_gap, spacing)
    if extra_p.shape[0]:
        p, normals = np.concatenate([p, extra_p]), np.concatenate([normals, extra_n])
    return p, normals


def _complete_corners(rims, fit2d, fit_layer, tree, half_across, max_gap, spacing):
    """Points closing the gap between a placed panel rim's end and a square rim's line, where the panel continues.

    Canny loses a panel's rim for a stretch near its corners (the smoothing rounds them, the
    corner's mixed layers break the chain): where a rim's end stops short of a perpendicular
    rim's line by at most ``max_gap`` and the perpendicular rim itself reaches to within
    ``max_gap`` of the corner, the rim is continued to the corner if the gap's band still
    has the panel on the rim's side (:func:`panel_side`; gaps under ``half_across`` need no
    check). Returns points and normals (K, 2) on the rims' lines, ``spacing`` apart.
    """
    out_p, out_n = [], []
    for i, (n, d, o, t_lo, t_hi) in enumerate(rims):
        for j, (n2, d2, o2, t2_lo, t2_hi) in enumerate(rims):
            if i == j or abs(n @ n2) > 1e-3:
                continue
            # The corner: on both lines.
            a = np.array([n, n2])
            corner = np.linalg.solve(a, np.array([o, o2]))
            tc, tc2 = float(corner @ d), float(corner @ d2)
            if min(abs(tc2 - t2_lo), abs(tc2 - t2_hi)) > max_gap and not (t2_lo <= tc2 <= t2_hi):
                continue
            for lo, hi in ((t_hi, tc), (tc, t_lo)):
                if not (0.0 < hi - lo <= max_gap):
                    continue
                if hi - lo > half_across:
                    mid = (0.5 * (lo + hi)) * d + o * n
                    cand = np.asarray(tree.query_ball_point(mid, float(np.hypot(0.5 * (hi - lo), half_across))), np.int64)
                    rel = fit2d[cand]
                    u, tt = rel @ n - o, rel @ d
                    band = (np.abs(u) <= half_across) & (tt >= lo) & (tt <= hi)
                    if panel_side(u[band], fit_layer[cand[band]]) == 0.0:
                        continue
                ts = np.arange(lo + spacing, hi, spacing)
                out_p.append(ts[:, None] * d + o * n)
                out_n.append(np.tile(n, (ts.size, 1)))
    if not out_p:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.concatenate(out_p), np.concatenate(out_n)
