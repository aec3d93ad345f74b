"""Brightness-gradient sign of contour points from the cloud's colour or intensity.

For a contour point ``p`` of region ``r`` with outward edge normal ``e`` we compare

* *inside*: the median intensity of region-``r`` points within ``radius`` of ``p`` that
  lie at least ``margin`` inside the edge (``(q - p).e < -margin``), and
* *outside*: the median intensity of points of any other surface within ``radius``
  of ``p`` that are not inside the edge (``(q - p).e > -margin``) - the adjacent wall
  below a roof edge, the ground beyond a low box, the box standing in a hole.

``brightness_sign`` is +1 if outside is brighter than inside by more than ``threshold``
(brightness rises along ``e``), -1 if darker, 0 if the difference is smaller or either
side has fewer than ``min_count`` points. Intensities are compared after scaling the
cloud's intensity range to [0, 1].
"""

from __future__ import annotations

import numpy as np


def intensity_from_colors(colors: np.ndarray) -> np.ndarray:
    """Luma (Rec. 601) of RGB colours in [0, 1], float64 (N,)."""
    c = np.asarray(colors, dtype=np.float64)
    if c.ndim == 1:
        return c
    return c[:, 0] * 0.299 + c[:, 1] * 0.587 + c[:, 2] * 0.114


def brightness_signs(
    points: np.ndarray,
    edge_normals: np.ndarray,
    region: np.ndarray,
    labels: np.ndarray,
    intensity: np.ndarray,
    tree,
    radius: float,
    margin: float,
    threshold: float,
    min_count: int = 3,
    k: int = 48,
) -> np.ndarray:
    """int8 sign per contour point (see module docstring)."""
    m = points.shape[0]
    out = np.zeros(m, np.int8)
    if m == 0:
        return out
    lo, hi = float(np.min(intensity)), float(np.max(intensity))
    if not hi > lo:
        return out
    inten = (intensity - lo) / (hi - lo)
    dist, idx = tree.query(points, k=k, distance_upper_bound=radius)
    dist = dist.reshape(m, -1)
    idx = idx.reshape(m, -1)
    valid = np.isfinite(dist)
    safe = np.where(valid, idx, 0)
    along = np.einsum("mkd,md->mk", tree.data[safe] - points[:, None, :], edge_normals)
    lab = labels[safe]
    val = inten[safe]
    own = lab == region[:, None]
    inside = valid & own & (along < -margin)
    outside = valid & ~own & (along > -margin)
    n_in = inside.sum(axis=1)
    n_out = outside.sum(axis=1)
    with np.errstate(all="ignore"):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med_in = np.nanmedian(np.where(inside, val, np.nan), axis=1)
            med_out = np.nanmedian(np.where(outside, val, np.nan), axis=1)
    diff = med_out - med_in
    ok = (n_in >= min_count) & (n_out >= min_count)
    out[ok & (diff > threshold)] = 1
    out[ok & (diff < -threshold)] = -1
    return out
