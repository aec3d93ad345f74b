"""Precision and recall of contour points against true edge segments.

* precision: fraction of contour points within ``tolerance_m`` of some true edge;
* recall: of the true edge length *visible in the scan* (edge samples with a raw cloud
  point within ``visible_radius_m``; all of it if no cloud is given), the fraction that
  has a contour point within ``tolerance_m``.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def point_segment_distances(points, segments):
    """Distance from each point (N, 3) to the nearest segment (M, 2, 3), float64 (N,)."""
    n = points.shape[0]
    m = segments.shape[0]
    out = np.full(n, np.inf)
    for j in range(m):
        ax, ay, az = segments[j, 0, 0], segments[j, 0, 1], segments[j, 0, 2]
        dx = segments[j, 1, 0] - ax
        dy = segments[j, 1, 1] - ay
        dz = segments[j, 1, 2] - az
        ll = dx * dx + dy * dy + dz * dz
        for i in range(n):
            px = points[i, 0] - ax
            py = points[i, 1] - ay
            pz = points[i, 2] - az
            t = 0.0
            if ll > 0.0:
                t = (px * dx + py * dy + pz * dz) / ll
                t = min(1.0, max(0.0, t))
            ex = px - t * dx
            ey = py - t * dy
            ez = pz - t * dz
            d = ex * ex + ey * ey + ez * ez
            if d < out[i]:
                out[i] = d
    return np.sqrt(out)


def sample_segments(segments: np.ndarray, step_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Points every ~``step_m`` along each segment (at sub-segment midpoints) and the length each stands for."""
    pts, w = [], []
    for a, b in segments:
        length = float(np.linalg.norm(b - a))
        if length == 0.0:
            continue
        n = max(1, int(np.ceil(length / step_m)))
        t = (np.arange(n) + 0.5) / n
        pts.append(a + t[:, None] * (b - a))
        w.append(np.full(n, length / n))
    if not pts:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(pts), np.concatenate(w)


def contour_precision_recall(
    contour_points: np.ndarray,
    edge_segments: np.ndarray,
    tolerance_m: float = 0.02,
    cloud: np.ndarray | None = None,
    visible_radius_m: float = 0.05,
    sample_step_m: float = 0.005,
) -> dict:
    """Precision/recall of ``contour_points`` (N, 3) against ``edge_segments`` (M, 2, 3), metres.

    ``cloud`` (K, 3): the raw scan; an edge sample counts as visible if a cloud point lies
    within ``visible_radius_m``. Returns ``precision``, ``recall`` (fractions),
    ``n_points``, ``median_distance_m``, ``p95_distance_m``, ``edge_length_m``,
    ``visible_length_m``, ``covered_length_m``.
    """
    from scipy.spatial import cKDTree

    cp = np.ascontiguousarray(contour_points, dtype=np.float64).reshape(-1, 3)
    seg = np.ascontiguousarray(edge_segments, dtype=np.float64).reshape(-1, 2, 3)
    dist = point_segment_distances(cp, seg) if cp.shape[0] and seg.shape[0] else np.full(cp.shape[0], np.inf)
    samples, weight = sample_segments(seg, sample_step_m)
    if cloud is not None and samples.shape[0]:
        d_cloud, _ = cKDTree(np.asarray(cloud, np.float64)).query(samples, k=1, distance_upper_bound=visible_radius_m)
        visible = np.isfinite(d_cloud)
    else:
        visible = np.ones(samples.shape[0], bool)
    if cp.shape[0] and samples.shape[0]:
        d_cont, _ = cKDTree(cp).query(samples, k=1, distance_upper_bound=tolerance_m)
        covered = np.isfinite(d_cont) & visible
    else:
        covered = np.zeros(samples.shape[0], bool)
    vis_len = float(weight[visible].sum())
    cov_len = float(weight[covered].sum())
    return {
        "precision": float(np.mean(dist <= tolerance_m)) if cp.shape[0] else 0.0,
        "recall": cov_len / vis_len if vis_len > 0 else 0.0,
        "n_points": int(cp.shape[0]),
        "median_distance_m": float(np.median(dist)) if cp.shape[0] else float("nan"),
        "p95_distance_m": float(np.percentile(dist, 95)) if cp.shape[0] else float("nan"),
        "edge_length_m": float(weight.sum()),
        "visible_length_m": vis_len,
        "covered_length_m": cov_len,
    }
