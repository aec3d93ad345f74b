"""A second region-growing pass over the points no region explained.

On a sparse scan (100 points/m^2, ~10 cm apart) a surface that lies a few centimetres to
a few point spacings from a larger parallel one - a sofa's or cabinet's back 5-10 cm in
front of the wall - has kNN neighbourhoods made mostly of the other surface's points. Its
normals are blended, its kNN graph is mostly links to the wall, and region growing breaks
it into fragments under ``min_region_points``, so it gets no region and no contour (the
first pass's diagnosis: sofa back 0/176 points in a kept region).

Once the first pass has explained the large surfaces, their points are out of the way: this
pass rebuilds neighbourhoods among the *unexplained* points only, where such a back face's
points are each other's neighbours, and grows regions there with the same rules. A new
region must be a surface, not a line: the points left along a crease or a scan rim form a
strip, so its spread along its minor in-plane axis must reach ``min_width_m``; and it must
be flatter than the noise tails a noisy plane leaves behind (rms under half
``plane_distance``).
"""

from __future__ import annotations

import numpy as np

from evpose.mapping.normals import estimate_neighbourhoods
from evpose.mapping.region_growing import fit_regions, grow_regions, merge_coplanar
from evpose.mapping.robust_normals import robust_normals


def grow_leftover_regions(points: np.ndarray, labels: np.ndarray, regions, indices: np.ndarray, k: int, cos_threshold: float,
                          curvature_limit: float, cos_plane: float, max_offset: float, cos_merge: float,
                          plane_distance: float, min_points: int, min_width_m: float,
                          robust_min_curvature: float) -> np.ndarray:
    """Labels with new regions (numbered after the first pass's ``regions``) grown over the unassigned points (label -1).

    ``k`` neighbours among the unassigned points; the angle/curvature/offset/merge limits are
    the first pass's (:func:`evpose.mapping.region_growing.grow_regions`,
    :func:`~evpose.mapping.region_growing.merge_coplanar`); a new region needs ``min_points``
    points, a standard deviation of at least ``min_width_m`` m along its minor in-plane
    axis and an rms plane distance under ``plane_distance / 2``. A new region parallel to a first-pass region it touches (``indices``: the full kNN
    graph) and off its plane by more than ``plane_distance`` but at most ``max_offset`` is dropped: that is the noise tail or the
    second layer of a surface already explained (a picture 2 cm proud of its wall), which
    the albedo path handles; a plane fitted to part of it only traces a ragged outline.
    Deterministic: depends only on the points and labels.
    """
    n_regions = regions.sizes.size
    left = np.flatnonzero(labels < 0)
    if left.size < max(min_points, k + 1):
        return labels
    sub = np.ascontiguousarray(points[left])
    nb = estimate_neighbourhoods(sub, k)
    normals, curvature = robust_normals(sub, nb.indices, nb.normals, nb.curvature, robust_min_curvature, plane_distance)
    lab = grow_regions(sub, normals, curvature, nb.indices, cos_threshold, curvature_limit, cos_plane, max_offset)
    lab, reg = fit_regions(sub, lab, 3)
    lab = merge_coplanar(sub, nb.indices, lab, reg, cos_merge, plane_distance)
    lab, reg = fit_regions(sub, lab, min_points)
    if reg.sizes.size == 0:
        return labels
    # Strips along creases and rims are lines, not surfaces. The first pass hands every point
    # within plane_distance of a plane to it, so what is left of a noisy plane is its noise
    # tails, beyond plane_distance on both sides: a "plane" through them has an rms of about
    # plane_distance, while a real surface's is the range noise, ~plane_distance / 3.
    ok = (reg.minor_std >= min_width_m) & (reg.rms <= 0.5 * plane_distance)
    for r in np.flatnonzero(ok):
        members = left[lab == r]
        touched = np.unique(labels[indices[members, 1:]])
        touched = touched[touched >= 0]
        if touched.size == 0:
            continue
        parallel = np.abs(regions.normals[touched] @ reg.normals[r]) >= cos_merge
        offset = np.abs(np.einsum("md,md->m", reg.centroids[r] - regions.centroids[touched], regions.normals[touched]))
        # On the plane itself it is a fragment of it, which the caller's merge joins.
        if np.any(parallel & (offset > plane_distance) & (offset <= max_offset)):
            ok[r] = False
    remap = np.full(reg.sizes.size + 1, -1, np.int32)
    remap[np.flatnonzero(ok)] = n_regions + np.arange(int(ok.sum()), dtype=np.int32)
    out = labels.copy()
    out[left] = remap[np.where(lab >= 0, lab, reg.sizes.size)]
    return out

