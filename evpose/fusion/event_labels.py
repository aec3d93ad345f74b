"""Labelling a step's events against the predicted polarity of the nearest projected map point (EV-Pose polarity filter).

``classify_events`` labels each event kept (its point's predicted polarity, or the
buffer zone), removed (the other polarity) or outside every patch;
``observed_point_polarity`` is the majority polarity per point (for sign learning);
``filter_summary`` the shares removed. Split from :mod:`evpose.fusion.polarity`
(which re-exports them) to keep files short.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def _majority_polarity(point, p, out):
    """Sign of the summed polarities of the events assigned to each point (``point`` < 0: unassigned)."""
    score = np.zeros(out.shape[0], np.int64)
    for i in range(point.shape[0]):
        k = point[i]
        if k >= 0:
            score[k] += p[i]
    for k in range(out.shape[0]):
        out[k] = 1 if score[k] > 0 else (-1 if score[k] < 0 else 0)


@nb.njit(cache=True)
def _nearest_point_grid(uv, radius, width, height):
    idx = np.full((height, width), -1, np.int32)
    dist = np.full((height, width), np.inf)
    r = int(np.ceil(radius))
    r2 = radius * radius
    for k in range(uv.shape[0]):
        u = uv[k, 0]
        v = uv[k, 1]
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        cu = int(np.floor(u + 0.5))
        cv = int(np.floor(v + 0.5))
        for yy in range(cv - r, cv + r + 1):
            if yy < 0 or yy >= height:
                continue
            for xx in range(cu - r, cu + r + 1):
                if xx < 0 or xx >= width:
                    continue
                d = (xx - u) * (xx - u) + (yy - v) * (yy - v)
                if d <= r2 and d < dist[yy, xx]:
                    dist[yy, xx] = d
                    idx[yy, xx] = k
    return idx


@nb.njit(cache=True)
def _classify(ex, ey, ep, grid, predicted, out_label, out_point):
    h, w = grid.shape
    for i in range(ex.shape[0]):
        x = int(np.floor(ex[i] + 0.5))
        y = int(np.floor(ey[i] + 0.5))
        k = -1
        if 0 <= x < w and 0 <= y < h:
            k = grid[y, x]
        out_point[i] = k
        if k < 0:
            out_label[i] = -1
        elif predicted[k] == 0 or predicted[k] == ep[i]:
            out_label[i] = 1
        else:
            out_label[i] = 0


def classify_events(x, y, p, projected_uv, predicted_polarity, radius_px: float, width: int, height: int):
    """Label events by the predicted polarity of the nearest projected map point within ``radius_px``.

    ``x``/``y`` must be in the same (ideal pinhole) pixel frame as ``projected_uv``.
    Returns ``(label int8 (E,), point int32 (E,))``: label 1 = kept (polarity
    matches or buffer zone), 0 = removed by the polarity filter, -1 = in no
    point's patch (unused by registration); point = index into ``projected_uv`` or -1.
    """
    uv = np.ascontiguousarray(projected_uv, np.float64).reshape(-1, 2)
    grid = _nearest_point_grid(uv, float(radius_px), int(width), int(height))
    ex = np.ascontiguousarray(x, np.float64)
    ey = np.ascontiguousarray(y, np.float64)
    ep = np.ascontiguousarray(p, np.int8)
    label = np.empty(ex.shape[0], np.int8)
    point = np.empty(ex.shape[0], np.int32)
    _classify(ex, ey, ep, grid, np.ascontiguousarray(predicted_polarity, np.int8), label, point)
    return label, point


def observed_point_polarity(point, p, n_points: int) -> np.ndarray:
    """Majority polarity of the events assigned to each point (from :func:`classify_events`), 0 if none or tied."""
    point = np.ascontiguousarray(point).ravel()
    p = np.ascontiguousarray(p).ravel()
    if point.dtype.kind not in "iu" or p.dtype.kind not in "iu":  # not labels and event polarities: weighted counts
        point, p = point.astype(np.int64), p.astype(np.float64)
        m = point >= 0
        return np.sign(np.bincount(point[m], weights=p[m], minlength=n_points)).astype(np.int8)
    out = np.empty(max(int(n_points), int(point.max()) + 1 if point.size else 0), np.int8)  # bincount's length
    _majority_polarity(point, p, out)  # integer sums: the same signs as the float bincount, without its copies
    return out


def filter_summary(label: np.ndarray) -> dict:
    """Share of events the polarity filter removed: of those in point patches, and of all."""
    n = int(label.size)
    inside = int(np.count_nonzero(label >= 0))
    removed = int(np.count_nonzero(label == 0))
    return {"events": n, "events_in_patches": inside, "events_removed": removed,
            "removed_share_of_patches": removed / inside if inside else 0.0, "removed_share_of_all": removed / n if n else 0.0}
