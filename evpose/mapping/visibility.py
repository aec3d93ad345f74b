"""Which points of a region a camera could see: the front layer where a region holds two."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def front_layer(points, labels, indices, centroids, plane_normals, depth, radius):
    """True for points a viewer on the plane-normal side of their region could see.

    Where a region holds two layers - a door or picture a couple of centimetres proud of a
    wall, and the wall behind it (a scan merged from many stations, or a simulator that
    samples every surface, has both) - the intensities mix both, but a camera sees only the
    front one. A point is hidden if a same-region neighbour within ``radius`` metres in the
    plane lies more than ``depth`` metres in front of it (along the viewer-facing plane
    normal). ``radius`` of a few point spacings finds a front point over nearly every point
    under a panel, and hides wall points only within about that distance beside it; the
    edge's position is then fitted to all points, so that halo costs no accuracy. On a
    single layer only range-noise outliers are hidden (a random thinning).
    """
    n, k = indices.shape
    out = np.ones(n, np.bool_)
    r2 = radius * radius
    for i in range(n):
        r = labels[i]
        if r < 0:
            continue
        nx, ny, nz = plane_normals[r, 0], plane_normals[r, 1], plane_normals[r, 2]
        for jj in range(1, k):
            j = indices[i, jj]
            if labels[j] != r:
                continue
            rx = points[j, 0] - points[i, 0]
            ry = points[j, 1] - points[i, 1]
            rz = points[j, 2] - points[i, 2]
            along = rx * nx + ry * ny + rz * nz
            if along <= depth:
                continue
            if rx * rx + ry * ry + rz * rz - along * along <= r2:
                out[i] = False
                break
    return out
