"""Region growing into smooth surfaces, plane fits, and extension of regions up to their edges.

Seeds are taken in order of increasing curvature; a region grows over the kNN graph to
neighbours whose normal differs by less than the angle threshold, and only neighbours
whose curvature is under the limit grow it further (the PCL scheme). Points right at an
edge have blended PCA normals and stay unassigned, which would leave every region one
neighbourhood radius short of its true edge; :func:`extend_to_planes` therefore hands
unassigned points to the adjacent region whose plane they lie on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np


@dataclass
class Regions:
    """Per-point region labels and a plane per region."""

    labels: np.ndarray
    """Region of each point, int32 (N,); -1 unassigned. Regions are numbered 0..R-1."""
    centroids: np.ndarray
    """Centroid of each region, float64 (R, 3), metres."""
    normals: np.ndarray
    """Unit plane normal of each region, float64 (R, 3)."""
    axes: np.ndarray
    """In-plane orthonormal axes (major, minor) of each region, float64 (R, 2, 3)."""
    rms: np.ndarray
    """RMS point-to-plane distance of each region, float64 (R,), metres."""
    sizes: np.ndarray
    """Number of points of each region, int64 (R,)."""
    minor_std: np.ndarray
    """Standard deviation of each region's points along its minor in-plane axis, float64 (R,), metres."""


@numba.njit(cache=True)
def grow_regions(points, normals, curvature, indices, cos_threshold, curvature_limit, cos_plane, max_offset):
    """Labels (int32, -1 = none) from smoothness-constrained region growing over the kNN graph.

    Besides the neighbour-to-neighbour angle (``cos_threshold``), a candidate's normal must stay
    within ``cos_plane`` of the region's running mean normal: PCA normals turn gradually across
    a rounded crease, and without this bound a region would creep around a box corner.
    A candidate must also lie within ``max_offset`` (m) of the region's running plane (mean
    normal through the running centroid): on a sparse scan the blended normals over a low
    step (a 15 cm landing pad) stay within the angle limits, and without this bound the
    pad's top would join the ground.
    """
    n, k = indices.shape
    labels = np.full(n, -1, np.int32)
    order = np.argsort(curvature, kind="mergesort")
    queue = np.empty(n, np.int64)
    region = 0
    for s in order:
        if curvature[s] > curvature_limit:
            break  # sorted: no later point can seed
        if labels[s] != -1:
            continue
        labels[s] = region
        mx = normals[s, 0]
        my = normals[s, 1]
        mz = normals[s, 2]
        cx = points[s, 0]
        cy = points[s, 1]
        cz = points[s, 2]
        count = 1.0
        head = 0
        tail = 0
        queue[tail] = s
        tail += 1
        while head < tail:
            i = queue[head]
            head += 1
            for jj in range(1, k):
                j = indices[i, jj]
                if labels[j] != -1:
                    continue
                d = normals[i, 0] * normals[j, 0] + normals[i, 1] * normals[j, 1] + normals[i, 2] * normals[j, 2]
                if abs(d) < cos_threshold:
                    continue
                dm = mx * normals[j, 0] + my * normals[j, 1] + mz * normals[j, 2]
                norm = np.sqrt(mx * mx + my * my + mz * mz)
                if abs(dm) < cos_plane * norm:
                    continue
                off = ((points[j, 0] - cx / count) * mx + (points[j, 1] - cy / count) * my
                       + (points[j, 2] - cz / count) * mz)
                if abs(off) > max_offset * norm:
                    continue
                cx += points[j, 0]
                cy += points[j, 1]
                cz += points[j, 2]
                count += 1.0
                sg = 1.0 if dm >= 0 else -1.0
                mx += sg * normals[j, 0]
                my += sg * normals[j, 1]
                mz += sg * normals[j, 2]
                labels[j] = region
                if curvature[j] <= curvature_limit:
                    queue[tail] = j
                    tail += 1
        region += 1
    return labels


@numba.njit(cache=True)
def _extend_pass(points, indices, labels, centroids, normals, max_distance):
    n, k = indices.shape
    out = labels.copy()
    changed = 0
    for i in range(n):
        if labels[i] != -1:
            continue
        best = -1
        best_d = max_distance
        for jj in range(1, k):
            r = labels[indices[i, jj]]
            if r < 0:
                continue
            d = abs((points[i, 0] - centroids[r, 0]) * normals[r, 0]
                    + (points[i, 1] - centroids[r, 1]) * normals[r, 1]
                    + (points[i, 2] - centroids[r, 2]) * normals[r, 2])
            if d < best_d or (d == best_d and best != -1 and r < best):
                best_d = d
                best = r
        if best != -1:
            out[i] = best
            changed += 1
    return out, changed


def extend_to_planes(points, indices, labels, regions: "Regions", max_distance: float, passes: int) -> np.ndarray:
    """Give unassigned points to the neighbouring region whose plane is nearest (within ``max_distance`` m).

    Synchronous passes (each reads the previous labels) keep the result independent of point order.
    """
    out = labels
    for _ in range(passes):
        out, changed = _extend_pass(points, indices, out, regions.centroids, regions.normals, max_distance)
        if changed == 0:
            break
    return out


def fit_regions(points: np.ndarray, labels: np.ndarray, min_size: int) -> tuple[np.ndarray, Regions]:
    """Drop regions under ``min_size`` points, renumber the rest by size (largest first), fit a plane to each."""
    valid = labels >= 0
    counts = np.bincount(labels[valid], minlength=0) if valid.any() else np.zeros(0, np.int64)
    keep = np.flatnonzero(counts >= min_size)
    # Largest first, ties by old id: a stable, order-independent numbering.
    keep = keep[np.lexsort((keep, -counts[keep]))]
    remap = np.full(counts.size + 1, -1, np.int32)
    remap[keep] = np.arange(keep.size, dtype=np.int32)
    new = remap[np.where(valid, labels, counts.size)]
    return new, refit_planes(points, new, keep.size)


def refit_planes(points: np.ndarray, labels: np.ndarray, n_regions: int) -> Regions:
    """Least-squares plane (PCA) of each region's points."""
    order = np.argsort(labels, kind="stable")
    sorted_labels = labels[order]
    starts = np.searchsorted(sorted_labels, np.arange(n_regions + 1))
    centroids = np.zeros((n_regions, 3))
    normals = np.zeros((n_regions, 3))
    axes = np.zeros((n_regions, 2, 3))
    rms = np.zeros(n_regions)
    sizes = np.zeros(n_regions, np.int64)
    minor = np.zeros(n_regions)
    for r in range(n_regions):
        p = points[order[starts[r]:starts[r + 1]]]
        c = p.mean(axis=0)
        w, v = np.linalg.eigh(np.cov((p - c).T) if p.shape[0] > 1 else np.eye(3))
        basis = [v[:, 0], v[:, 2], v[:, 1]]
        # Deterministic signs: the largest-magnitude component of each vector is positive.
        basis = [b * (1.0 if b[np.argmax(np.abs(b))] > 0 else -1.0) for b in basis]
        n, a0, a1 = basis
        a1 = np.cross(n, a0)  # right-handed (a0, a1, n)
        centroids[r], normals[r], axes[r, 0], axes[r, 1] = c, n, a0, a1
        rms[r] = float(np.sqrt(np.mean(((p - c) @ n) ** 2)))
        sizes[r] = p.shape[0]
        minor[r] = float(np.sqrt(max(w[1], 0.0)))
    return Regions(labels.astype(np.int32), centroids, normals, axes, rms, sizes, minor)


def merge_coplanar(points, indices, labels, regions: "Regions", cos_angle: float, max_distance: float,
                   min_links: int = 3) -> np.ndarray:
    """Merge neighbouring regions that are one plane split by noise (union-find over kNN links).

    Two regions merge when at least ``min_links`` kNN links join them, their normals agree
    within ``acos(cos_angle)`` and, over those links, points lie on average within
    ``max_distance`` m of the other region's plane. Returns new labels (not renumbered).
    """
    n, k = indices.shape
    src = np.repeat(np.arange(n), k - 1)
    dst = indices[:, 1:].reshape(-1)
    a = labels[src]
    b = labels[dst]
    link = (a >= 0) & (b >= 0) & (a != b)
    if not link.any():
        return labels
    src, dst, a, b = src[link], dst[link], a[link], b[link]
    d = 0.5 * (np.abs(np.einsum("md,md->m", points[dst] - regions.centroids[a], regions.normals[a]))
               + np.abs(np.einsum("md,md->m", points[src] - regions.centroids[b], regions.normals[b])))
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    n_reg = regions.sizes.size
    key = lo.astype(np.int64) * n_reg + hi
    uniq, inv, counts = np.unique(key, return_inverse=True, return_counts=True)
    mean_d = np.bincount(inv, weights=d) / counts
    pa, pb = uniq // n_reg, uniq % n_reg
    cos = np.abs(np.einsum("md,md->m", regions.normals[pa], regions.normals[pb]))
    ok = (counts >= min_links) & (cos >= cos_angle) & (mean_d <= max_distance)
    parent = np.arange(n_reg)

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for x, y in zip(pa[ok], pb[ok]):  # uniq is sorted: a fixed merge order
        rx, ry = find(int(x)), find(int(y))
        if rx != ry:
            parent[max(rx, ry)] = min(rx, ry)
    roots = np.array([find(i) for i in range(n_reg)])
    out = labels.copy()
    valid = labels >= 0
    out[valid] = roots[labels[valid]]
    return out
