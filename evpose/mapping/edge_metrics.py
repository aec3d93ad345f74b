"""Precision and recall of contour points against true edge segments.

* precision: fraction of contour points within ``tolerance_m`` of some true edge;
* recall: of the true edge length *visible in the scan*, the fraction that has a contour
  point within ``tolerance_m``.

"Visible in the scan" has two definitions:

* without ``faces`` (the old one): an edge sample with *any* raw cloud point within
  ``visible_radius_m`` (all of the edge if no cloud is given). Any surface counts - the
  wall 5 cm behind a shelf's back edge makes that edge "visible" where the shelf itself
  was not sampled, and a sample whose own surfaces were scanned 6 cm away does not.
* with ``faces`` (:func:`edge_faces`, the faithful one): an edge is where two surfaces
  meet, and the scan shows it where it samples *both* of them near it: an edge sample is
  visible when, for each of its two faces, a cloud point lies within ``visible_radius_m``
  of it and within ``face_tolerance_m`` (~3x range noise) of that face's plane. The plane
  counts on either side of the edge: a box resting on the ground has no scanned bottom
  face, but its bottom face's plane beyond the edge is the ground the crease is formed
  with. Segments without faces (painted edges, all-zero rows) keep the old rule. The
  radius should be about the scan's point spacing (``1/sqrt(density)``): a face is
  "sampled near" the edge when a point of it is no farther than a typical gap.
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


def edge_faces(segments: np.ndarray, decimals: int = 6) -> np.ndarray:
    """The two faces meeting at each edge of a polyhedral edge set, from the edges sharing its ends.

    ``segments`` (M, 2, 3), e.g. boxes' 12 edges each. Returns (M, 2, 2, 3): per segment and
    face, (unit direction into the face perpendicular to the edge, unit face normal). At a
    box corner the two other edges give the two faces' directions. Rows stay zero where an
    end does not have exactly two other, non-collinear edges (a polyline of painted edges,
    a vertex shared by several boxes) - those segments keep the plain visibility rule.
    Endpoints are matched after rounding to ``decimals``.
    """
    seg = np.asarray(segments, np.float64).reshape(-1, 2, 3)
    at: dict[tuple, list[int]] = {}
    for j in range(seg.shape[0]):
        for e in range(2):
            at.setdefault(tuple(np.round(seg[j, e], decimals)), []).append(j)
    out = np.zeros((seg.shape[0], 2, 2, 3))
    for j in range(seg.shape[0]):
        e_dir = seg[j, 1] - seg[j, 0]
        length = float(np.linalg.norm(e_dir))
        if length == 0.0:
            continue
        e_dir /= length
        for end in range(2):
            a = seg[j, end]
            dirs = []
            for k in at[tuple(np.round(a, decimals))]:
                if k == j:
                    continue
                other = seg[k, 1] if np.allclose(seg[k, 0], a, atol=10.0 ** -decimals) else seg[k, 0]
                d = other - a
                d -= (d @ e_dir) * e_dir
                nd = float(np.linalg.norm(d))
                if nd > 1e-9:
                    dirs.append(d / nd)
            if len(dirs) == 2 and abs(float(dirs[0] @ dirs[1])) < 0.999:
                for f, d in enumerate(dirs):
                    out[j, f, 0] = d
                    out[j, f, 1] = np.cross(e_dir, d)
                break
    return out


def _face_visible(samples: np.ndarray, sample_seg: np.ndarray, faces: np.ndarray, cloud: np.ndarray, tree,
                  radius: float, face_tol: float) -> np.ndarray:
    """Per edge sample: True where each of its segment's two faces has a cloud point within ``radius`` on its plane."""
    near = tree.query_ball_point(samples, radius)
    counts = np.fromiter((len(x) for x in near), np.int64, samples.shape[0])
    owner = np.repeat(np.arange(samples.shape[0]), counts)
    idx = np.fromiter((i for x in near for i in x), np.int64, int(counts.sum()))
    rel = cloud[idx] - samples[owner]
    ok = np.ones(samples.shape[0], bool)
    for f in range(2):
        normal = faces[sample_seg[owner], f, 1]
        on = np.abs(np.einsum("ij,ij->i", rel, normal)) <= face_tol
        has = np.zeros(samples.shape[0], bool)
        has[owner[on]] = True
        ok &= has
    return ok


def _sample_segments_owned(segments: np.ndarray, step_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`sample_segments` plus the index of the segment each sample lies on."""
    counts = [max(1, int(np.ceil(float(np.linalg.norm(b - a)) / step_m))) if np.any(b != a) else 0 for a, b in segments]
    pts, w = sample_segments(segments, step_m)
    return pts, w, np.repeat(np.arange(len(counts)), counts).astype(np.int64)


def contour_precision_recall(
    contour_points: np.ndarray,
    edge_segments: np.ndarray,
    tolerance_m: float = 0.02,
    cloud: np.ndarray | None = None,
    visible_radius_m: float = 0.05,
    sample_step_m: float = 0.005,
    faces: np.ndarray | None = None,
    face_tolerance_m: float = 0.015,
) -> dict:
    """Precision/recall of ``contour_points`` (N, 3) against ``edge_segments`` (M, 2, 3), metres.

    ``cloud`` (K, 3): the raw scan; an edge sample counts as visible if a cloud point lies
    within ``visible_radius_m`` - or, with ``faces`` (M, 2, 2, 3) from :func:`edge_faces`,
    if both of its faces have a cloud point within ``visible_radius_m`` and
    ``face_tolerance_m`` of their planes (module docstring). Returns ``precision``, ``recall`` (fractions),
    ``n_points``, ``median_distance_m``, ``p95_distance_m``, ``edge_length_m``,
    ``visible_length_m``, ``covered_length_m``.
    """
    from scipy.spatial import cKDTree

    cp = np.ascontiguousarray(contour_points, dtype=np.float64).reshape(-1, 3)
    seg = np.ascontiguousarray(edge_segments, dtype=np.float64).reshape(-1, 2, 3)
    dist = point_segment_distances(cp, seg) if cp.shape[0] and seg.shape[0] else np.full(cp.shape[0], np.inf)
    samples, weight, sample_seg = _sample_segments_owned(seg, sample_step_m)
    if cloud is not None and samples.shape[0]:
        cl = np.asarray(cloud, np.float64)
        tree = cKDTree(cl)
        d_cloud, _ = tree.query(samples, k=1, distance_upper_bound=visible_radius_m)
        visible = np.isfinite(d_cloud)
        if faces is not None:
            fc = np.asarray(faces, np.float64).reshape(seg.shape[0], 2, 2, 3)
            has_faces = np.abs(fc).sum(axis=(1, 2, 3))[sample_seg] > 0
            by_face = _face_visible(samples, sample_seg, fc, cl, tree, visible_radius_m, face_tolerance_m)
            visible = np.where(has_faces, by_face, visible)
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
