"""Geometry between regions: snapping contour points onto plane intersections, orienting plane normals.

Where two fitted planes meet at a crease (a box's top and wall, a wall and the ground),
the true edge is their line of intersection. The planes are fitted to thousands of
points, so that line is far more precise than any boundary traced from noisy points;
contour points next to a non-parallel adjacent region are projected onto it.
"""

from __future__ import annotations

import numpy as np


def snap_to_intersections(
    points: np.ndarray,
    region: np.ndarray,
    labels: np.ndarray,
    tree,
    plane_c: np.ndarray,
    plane_n: np.ndarray,
    radius: float,
    min_angle_rad: float,
    max_shift: float,
    reliable: np.ndarray | None = None,
    k: int = 16,
    outward: np.ndarray | None = None,
    across_tol: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Project contour points onto the intersection line of their plane and the nearest other region's plane.

    ``points`` (M, 3) lie on the plane of ``region`` (M,). A point is moved only if a cloud
    point of another region lies within ``radius`` m, the planes differ by at least
    ``min_angle_rad``, and the move is shorter than ``max_shift`` m.
    ``reliable`` (R,) bool: regions whose plane is trustworthy as a snap target (a narrow
    strip such as the 15 cm side of a low step has a poorly constrained tilt, and its
    intersection line would be wrong); None = all.
    ``outward`` (M, 3) unit in-plane outward normals of the contour points: then, of the
    candidate creases whose move is across the edge (tangential part under ``across_tol`` m),
    the innermost one is taken rather than the nearest cloud point's. Behind a sofa 10 cm in
    front of a wall, the top's rim has the sofa's back and the wall within reach, both
    across its edge; the rim is where the region ends, so the first surface met going
    outward - the back - is the one it meets. Points without such a candidate keep the
    nearest-point rule.
    Returns the new points and the adjacent region per point (-1 where none).
    """
    m = points.shape[0]
    out = points.copy()
    adjacent = np.full(m, -1, np.int32)
    if m == 0:
        return out, adjacent
    dist, idx = tree.query(points, k=k, distance_upper_bound=radius)
    dist = dist.reshape(m, -1)
    idx = idx.reshape(m, -1)
    valid = np.isfinite(dist)
    nb_lab = np.where(valid, labels[np.where(valid, idx, 0)], -1)
    other = (nb_lab >= 0) & (nb_lab != region[:, None])
    if reliable is not None:
        other &= reliable[np.maximum(nb_lab, 0)]
    # Only a plane that meets this one at an angle defines a crease: a parallel surface close
    # by (a wall 5 cm behind a shelf's back) must not hide the floor the back stands on.
    cos_nb = np.abs(np.einsum("mkd,md->mk", plane_n[np.maximum(nb_lab, 0)], plane_n[region]))
    other &= cos_nb < np.cos(min_angle_rad)
    has = other.any(axis=1)
    first = np.argmax(other, axis=1)  # nearest qualifying neighbour (query results are sorted)
    if outward is not None and has.any():
        first = _innermost_across(points, region, nb_lab, other, first, plane_c, plane_n, outward, across_tol)
    s = np.where(has, nb_lab[np.arange(m), first], -1)
    r = region
    ok = s >= 0
    nr = plane_n[r]
    ns = plane_n[np.where(ok, s, 0)]
    cosang = np.abs(np.einsum("md,md->m", nr, ns))
    ok &= cosang < np.cos(min_angle_rad)
    # Closest point x to p with n_r.x = h_r and n_s.x = h_s (Lagrange; 2x2 Gram system).
    hr = np.einsum("md,md->m", nr, plane_c[r])
    hs = np.einsum("md,md->m", ns, plane_c[np.where(ok, s, 0)])
    g11 = np.ones(m)
    g12 = np.einsum("md,md->m", nr, ns)
    g22 = np.ones(m)
    det = g11 * g22 - g12 * g12
    ok &= det > 1e-9
    det = np.where(ok, det, 1.0)
    rr = np.einsum("md,md->m", nr, points) - hr
    rs = np.einsum("md,md->m", ns, points) - hs
    lam_r = (g22 * rr - g12 * rs) / det
    lam_s = (g11 * rs - g12 * rr) / det
    x = points - lam_r[:, None] * nr - lam_s[:, None] * ns
    ok &= np.linalg.norm(x - points, axis=1) < max_shift
    out[ok] = x[ok]
    adjacent[ok] = s[ok]
    return out, adjacent


def _crease_points(points, nr, hr, ns, hs):
    """Closest point to ``points`` on the intersection of planes (nr, hr) and (ns, hs); NaN where parallel."""
    g12 = np.einsum("...d,...d->...", nr, ns)
    det = 1.0 - g12 * g12
    det = np.where(det > 1e-9, det, np.nan)
    rr = np.einsum("...d,...d->...", nr, points) - hr
    rs = np.einsum("...d,...d->...", ns, points) - hs
    lam_r = (rr - g12 * rs) / det
    lam_s = (rs - g12 * rr) / det
    return points - lam_r[..., None] * nr - lam_s[..., None] * ns


def _innermost_across(points, region, nb_lab, other, first, plane_c, plane_n, outward, across_tol):
    """Per point, the neighbour column whose region's crease is reached by a move across the edge and lies innermost."""
    m, k = nb_lab.shape
    cand = np.maximum(nb_lab, 0)
    nr = np.broadcast_to(plane_n[region][:, None, :], (m, k, 3))
    hr = np.einsum("md,md->m", plane_n[region], plane_c[region])[:, None]
    ns = plane_n[cand]
    hs = np.einsum("mkd,mkd->mk", ns, plane_c[cand])
    p = np.broadcast_to(points[:, None, :], (m, k, 3))
    with np.errstate(invalid="ignore"):
        move = _crease_points(p, nr, hr, ns, hs) - p
        along = np.einsum("mkd,md->mk", move, outward)
        tangential = np.linalg.norm(move - along[..., None] * outward[:, None, :], axis=2)
        ok = other & np.isfinite(along) & (tangential <= across_tol)
    along = np.where(ok, along, np.inf)
    best = np.argmin(along, axis=1)
    return np.where(ok.any(axis=1), best, first)


def orient_plane_normals(
    normals: np.ndarray,
    centroids: np.ndarray,
    points: np.ndarray,
    labels: np.ndarray,
    input_normals: np.ndarray | None,
    viewpoint: np.ndarray | None,
    reach: float,
    bounds: np.ndarray | None = None,
) -> np.ndarray:
    """Give each region's plane normal a sign that points to the side the surface is seen from.

    In order of preference: the majority sign of the input cloud's own normals; towards
    ``viewpoint``; for non-vertical planes (|n_z| >= 0.5) up (+z, z-up worlds); for
    vertical planes towards the side where the ground (points of non-vertical regions
    lower than the plane's centroid, within ``reach`` m of it) lies - the ground in front
    of a building wall or a room wall is what the scanner stood on. Falls back to the
    direction from the plane to the cloud's centre. ``bounds`` (R, 2, 3): each region's
    bounding box (computed here if None).
    """
    from evpose.mapping.spatial import BoxIndex

    out = normals.copy()
    n_reg = normals.shape[0]
    if n_reg == 0:
        return out
    if input_normals is not None:
        valid = labels >= 0
        dots = np.einsum("nd,nd->n", input_normals[valid], normals[labels[valid]])
        votes = np.bincount(labels[valid], weights=np.sign(dots), minlength=n_reg)
        sign = np.where(votes < 0, -1.0, 1.0)
        return out * sign[:, None]
    if viewpoint is not None:
        d = np.einsum("rd,rd->r", np.asarray(viewpoint)[None, :] - centroids, normals)
        return out * np.where(d < 0, -1.0, 1.0)[:, None]
    horizontal = np.abs(normals[:, 2]) >= 0.5
    out[horizontal] *= np.where(normals[horizontal, 2] < 0, -1.0, 1.0)[:, None]
    ground_mask = (labels >= 0) & horizontal[np.maximum(labels, 0)]
    gpts = points[ground_mask]
    centre = points.mean(axis=0)
    if bounds is None:
        bounds = np.stack([[points[labels == r].min(axis=0), points[labels == r].max(axis=0)] for r in range(n_reg)])
    index = BoxIndex(gpts) if gpts.shape[0] else None
    for r in np.flatnonzero(~horizontal):
        c, n = centroids[r], normals[r]
        hi = bounds[r, 1] + reach
        hi[2] = min(hi[2], c[2])  # only ground lower than the plane's centre
        box = index.query(bounds[r, 0] - reach, hi) if index is not None else np.zeros(0, np.int64)
        off = (gpts[box] - c) @ n
        off = off[(np.abs(off) > 1e-3) & (np.abs(off) < reach)]
        vote = float(np.sum(np.sign(off)))
        if vote == 0.0:
            vote = float((centre - c) @ n)
        if vote < 0:
            out[r] = -n
    return out


def snap_to_steps(
    points: np.ndarray,
    edge_normals: np.ndarray,
    region: np.ndarray,
    movable: np.ndarray,
    cloud: np.ndarray,
    labels: np.ndarray,
    tree,
    plane_n: np.ndarray,
    radius: float,
    min_offset: float,
    max_offset: float,
    max_shift: float,
    min_count: int = 3,
    k: int = 32,
) -> np.ndarray:
    """Move contour points of a low step onto the step's face, measured from the face's own points.

    A landing pad 15 cm high on a sparse scan has no region on its sides, so there is no
    crease to snap to, and the boundary estimated from the top's (or the ground's) points
    alone scatters by centimetres. The side's points, though, are there: points of other
    surfaces (or unassigned) within ``radius`` of the contour point, between ``min_offset``
    and ``max_offset`` off the region's plane and within ``max_shift`` of the edge along the
    edge normal mark where the face is. Points in ``movable`` (not already on a crease) are
    moved along their edge normal to the median position of those points.
    """
    out = points.copy()
    m = points.shape[0]
    if m == 0 or not movable.any():
        return out
    sel = np.flatnonzero(movable)
    dist, idx = tree.query(points[sel], k=k, distance_upper_bound=radius)
    dist = dist.reshape(sel.size, -1)
    idx = idx.reshape(sel.size, -1)
    valid = np.isfinite(dist)
    safe = np.where(valid, idx, 0)
    rel = cloud[safe] - points[sel][:, None, :]
    off = np.abs(np.einsum("mkd,md->mk", rel, plane_n[region[sel]]))
    along = np.einsum("mkd,md->mk", rel, edge_normals[sel])
    face = valid & (labels[safe] != region[sel][:, None]) & (off >= min_offset) & (off <= max_offset)
    face &= np.abs(along) <= max_shift
    count = face.sum(axis=1)
    ok = count >= min_count
    if ok.any():
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            shift = np.nanmedian(np.where(face, along, np.nan), axis=1)
        rows = sel[ok]
        out[rows] += shift[ok, None] * edge_normals[rows]
    return out


def crease_axes(contour_region: np.ndarray, crease: np.ndarray, normals: np.ndarray, axes: np.ndarray,
                min_points: int = 20, min_coherence: float = 0.5) -> np.ndarray:
    """Each region's outline direction from the crease lines its contour was snapped to, radians (modulo 90 degrees) or NaN.

    The direction of a crease is the cross product of two planes fitted to thousands of points:
    far steadier than the traced outline's own normals, whose raster steps and holes tilt a wall's
    dominant direction by up to ~1.3 degrees (1.4 cm over a 2 m door). ``contour_region`` (M,)
    and ``crease`` (M,) (the other region per contour point, -1 none) from the snap; creases
    with under ``min_points`` contour points are ignored. Angles are in the frame
    ``axes[r]`` (R, 2, 3) as :func:`evpose.mapping.step_fit.dominant_axis` gives them;
    ``min_coherence`` as there (a region's creases must be mostly square to each other).
    """
    out = np.full(axes.shape[0], np.nan)
    sel = crease >= 0
    if not sel.any():
        return out
    pairs, counts = np.unique(np.stack([contour_region[sel], crease[sel]], axis=1), axis=0, return_counts=True)
    for r in np.unique(pairs[:, 0]):
        z, wsum = 0j, 0.0
        for (_, r2), cnt in zip(pairs[pairs[:, 0] == r], counts[pairs[:, 0] == r]):
            if cnt < min_points:
                continue
            d = np.cross(normals[r], normals[r2])
            d2 = np.array([d @ axes[r][0], d @ axes[r][1]])
            if np.linalg.norm(d2) < 1e-9:
                continue
            z += cnt * np.exp(4j * np.arctan2(d2[1], d2[0]))
            wsum += cnt
        if wsum > 0 and abs(z) / wsum >= min_coherence:
            out[r] = float(np.angle(z)) / 4.0
    return out
