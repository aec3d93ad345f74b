"""A coarse 2D (x, y) bucket grid over a cloud for axis-aligned box queries.

Per-region work (rim tests, normal orientation) needs the cloud points inside the
region's bounding box; scanning all N points for each of R regions is O(N R) and
dominates million-point builds. Points are sorted once by bucket; a box query gathers
the buckets it overlaps and filters only their points.
"""

from __future__ import annotations

import numpy as np


class BoxIndex:
    """Points bucketed on an x-y grid of ``cell`` metres."""

    def __init__(self, points: np.ndarray, cell: float | None = None):
        self.points = points
        lo = points[:, :2].min(axis=0)
        extent = float(np.max(points[:, :2].max(axis=0) - lo))
        # ~256 buckets a side by default: small enough to be selective, large enough to be cheap.
        self.cell = cell if cell else max(extent / 256.0, 1e-3)
        self.lo = lo
        ij = np.floor((points[:, :2] - lo) / self.cell).astype(np.int64)
        self.nx = int(ij[:, 0].max()) + 1
        self.ny = int(ij[:, 1].max()) + 1
        key = ij[:, 0] * self.ny + ij[:, 1]
        self.order = np.argsort(key, kind="stable")
        self.starts = np.searchsorted(key[self.order], np.arange(self.nx * self.ny + 1))

    def query(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Sorted indices of the points with ``lo <= p <= hi`` (3D box, metres)."""
        i0, j0 = np.floor((lo[:2] - self.lo) / self.cell).astype(np.int64)
        i1, j1 = np.floor((hi[:2] - self.lo) / self.cell).astype(np.int64)
        i0, j0 = max(i0, 0), max(j0, 0)
        i1, j1 = min(i1, self.nx - 1), min(j1, self.ny - 1)
        if i0 > i1 or j0 > j1:
            return np.zeros(0, np.int64)
        ii = np.arange(i0, i1 + 1)
        # Buckets of one grid column are contiguous in key order: one range per column.
        a = self.starts[ii * self.ny + j0]
        b = self.starts[ii * self.ny + j1 + 1]
        lengths = b - a
        total = int(lengths.sum())
        if total == 0:
            return np.zeros(0, np.int64)
        offsets = np.repeat(a - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
        cand = self.order[np.arange(total) + offsets]
        p = self.points[cand]
        inside = np.all((p >= lo) & (p <= hi), axis=1)
        return np.sort(cand[inside])
