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


def mid_layer_depth(edge_points, edge_region, points, labels, visible, tree, plane_normals, radius, layer_m,
                    min_count=3):
    """Edge points moved along their region's plane normal to half-way between two layers, where there are two.

    A brightness edge of a panel a couple of centimetres proud of a wall (a picture, a door)
    is traced in the wall's fitted plane, near the back layer, although it is the rim of a
    step: the panel's front face on one side, the wall on the other. Where the region's
    points within ``radius`` m of an edge point hold both hidden points (behind the front
    layer, :func:`front_layer`) and visible points at least ``layer_m`` in front of their
    median (``min_count`` of each), the point is put at the mid-depth of the two layers -
    within half the step height of both rims. Elsewhere it stays. ``plane_normals`` (R, 3)
    face the viewer. Returns the new (M, 3) points.
    """
    out = np.array(edge_points, np.float64, copy=True)
    if out.shape[0] == 0:
        return out
    for i, near in enumerate(tree.query_ball_point(out, radius)):
        near = np.asarray(near, np.int64)
        r = edge_region[i]
        near = near[labels[near] == r]
        if near.size < 2 * min_count:
            continue
        off = (points[near] - out[i]) @ plane_normals[r]
        hid = ~visible[near]
        if hid.sum() < min_count:
            continue
        back = float(np.median(off[hid]))
        front_sel = (~hid) & (off > back + layer_m)
        if front_sel.sum() < min_count:
            continue
        out[i] += 0.5 * (float(np.median(off[front_sel])) + back) * plane_normals[r]
    return out
