"""Voxel downsampling, k-nearest neighbours and PCA normals/curvature of a raw cloud.

Curvature is the surface variation ``lambda0 / (lambda0 + lambda1 + lambda2)`` of the
covariance of a point's k nearest neighbours (EV-Pose, section VI-B); the normal is the
eigenvector of ``lambda0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np


@dataclass
class Neighbourhoods:
    """The k-nearest-neighbour graph of a cloud and the PCA quantities derived from it."""

    indices: np.ndarray
    """Neighbour indices, int64 (N, k); column 0 is the point itself."""
    distances: np.ndarray
    """Distances to the neighbours, float64 (N, k), metres."""
    normals: np.ndarray
    """Unit PCA normals (eigenvector of the smallest eigenvalue), float64 (N, 3); sign arbitrary."""
    curvature: np.ndarray
    """Surface variation lambda0/(lambda0+lambda1+lambda2), float64 (N,); 1 where undefined."""
    spacing: float
    """Median distance to the nearest other point, metres."""
    tree: object
    """The scipy cKDTree over the points (reused for later neighbourhood queries)."""


def voxel_downsample(points: np.ndarray, voxel: float, *extras: np.ndarray | None):
    """Average the points (and each optional per-point array in ``extras``) per voxel of edge ``voxel`` metres.

    Deterministic: voxels are ordered by their integer key, not by a hash table.
    Returns ``(points, *extras)``; ``None`` extras stay ``None``.
    """
    if voxel <= 0:
        return (points, *extras)
    keys = np.floor((points - points.min(axis=0)) / voxel).astype(np.int64)
    dims = keys.max(axis=0) + 1
    flat = (keys[:, 0] * dims[1] + keys[:, 1]) * dims[2] + keys[:, 2]
    _, inverse, counts = np.unique(flat, return_inverse=True, return_counts=True)
    out = []
    for arr in (points, *extras):
        if arr is None:
            out.append(None)
            continue
        a = np.asarray(arr, dtype=np.float64)
        a2 = a.reshape(a.shape[0], -1)
        acc = np.zeros((counts.size, a2.shape[1]), np.float64)
        for c in range(a2.shape[1]):
            acc[:, c] = np.bincount(inverse, weights=a2[:, c], minlength=counts.size)
        acc /= counts[:, None]
        out.append(acc.reshape((counts.size,) + a.shape[1:]))
    # Averaged normals are no longer unit length.
    return tuple(out)


@numba.njit(cache=True)
def _covariances(points, indices):
    n, k = indices.shape
    cov = np.empty((n, 3, 3), np.float64)
    for i in range(n):
        mx = 0.0
        my = 0.0
        mz = 0.0
        for j in range(k):
            q = indices[i, j]
            mx += points[q, 0]
            my += points[q, 1]
            mz += points[q, 2]
        mx /= k
        my /= k
        mz /= k
        sxx = sxy = sxz = syy = syz = szz = 0.0
        for j in range(k):
            q = indices[i, j]
            dx = points[q, 0] - mx
            dy = points[q, 1] - my
            dz = points[q, 2] - mz
            sxx += dx * dx
            sxy += dx * dy
            sxz += dx * dz
            syy += dy * dy
            syz += dy * dz
            szz += dz * dz
        cov[i, 0, 0] = sxx / k
        cov[i, 0, 1] = cov[i, 1, 0] = sxy / k
        cov[i, 0, 2] = cov[i, 2, 0] = sxz / k
        cov[i, 1, 1] = syy / k
        cov[i, 1, 2] = cov[i, 2, 1] = syz / k
        cov[i, 2, 2] = szz / k
    return cov


def estimate_neighbourhoods(points: np.ndarray, k: int, chunk: int = 200_000) -> Neighbourhoods:
    """kNN graph (scipy cKDTree) and PCA normals/curvature for every point."""
    from scipy.spatial import cKDTree

    pts = np.ascontiguousarray(points, dtype=np.float64)
    k = int(min(k, pts.shape[0]))
    tree = cKDTree(pts)
    dist, idx = tree.query(pts, k=k)
    dist = np.asarray(dist, np.float64).reshape(pts.shape[0], k)
    idx = np.ascontiguousarray(np.asarray(idx, np.int64).reshape(pts.shape[0], k))
    normals = np.empty_like(pts)
    curvature = np.empty(pts.shape[0], np.float64)
    # Chunks bound the (n, 3, 3) covariance memory on million-point clouds.
    for s in range(0, pts.shape[0], chunk):
        cov = _covariances(pts, idx[s:s + chunk])
        w, v = np.linalg.eigh(cov)
        total = w.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.where(total > 0, np.maximum(w[:, 0], 0.0) / total, 1.0)
        curvature[s:s + chunk] = c
        normals[s:s + chunk] = v[:, :, 0]
    spacing = float(np.median(dist[:, 1])) if k > 1 else 0.0
    return Neighbourhoods(idx, dist, normals, curvature, spacing, tree)
