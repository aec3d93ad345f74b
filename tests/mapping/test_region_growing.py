"""Region growing, coplanar merging and extension of regions up to their edges."""

from __future__ import annotations

import math

import numpy as np

from evpose.mapping.normals import estimate_neighbourhoods
from evpose.mapping.region_growing import extend_to_planes, fit_regions, grow_regions, merge_coplanar


def _fold(n=4000, seed=0, noise=0.0):
    """Two unit squares meeting at 90 degrees along the x axis."""
    rng = np.random.default_rng(seed)
    a = np.column_stack([rng.random(n), rng.random(n), np.zeros(n)])
    b = np.column_stack([rng.random(n), np.zeros(n), rng.random(n)])
    pts = np.vstack([a, b])
    return pts + rng.normal(0, noise, pts.shape) if noise else pts


def _grow(pts, k=16, angle=15.0, plane=25.0, curv=0.06):
    nb = estimate_neighbourhoods(pts, k)
    lab = grow_regions(pts, nb.normals, nb.curvature, nb.indices, math.cos(math.radians(angle)), curv,
                       math.cos(math.radians(plane)), 0.045)
    return nb, lab


def test_two_faces_of_a_fold_become_two_regions_that_do_not_cross_the_crease():
    pts = _fold()
    nb, lab = _grow(pts)
    lab, regions = fit_regions(pts, lab, 50)
    assert regions.sizes.size == 2
    normals = np.abs(regions.normals)
    assert sorted(np.argmax(normals, axis=1).tolist()) == [1, 2]
    # No region holds points of both faces away from the crease.
    for r in range(2):
        sel = lab == r
        assert min(np.sum(sel & (pts[:, 2] > 0.1)), np.sum(sel & (pts[:, 1] > 0.1))) == 0


def test_extension_hands_crease_points_to_the_plane_they_lie_on():
    pts = _fold()
    nb, lab = _grow(pts)
    lab, regions = fit_regions(pts, lab, 50)
    before = np.sum(lab == -1)
    ext = extend_to_planes(pts, nb.indices, lab, regions, 0.005, 4)
    assert before > 0 and np.sum(ext == -1) < 0.1 * before
    flat = ext >= 0
    d = np.abs(np.einsum("nd,nd->n", pts[flat] - regions.centroids[ext[flat]], regions.normals[ext[flat]]))
    assert d.max() <= 0.005


def test_noise_fragments_of_one_plane_are_merged():
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.random(6000), rng.random(6000), rng.normal(0, 0.006, 6000)])
    nb, lab = _grow(pts, k=16, angle=10.0, curv=0.06)
    lab, regions = fit_regions(pts, lab, 3)
    assert regions.sizes.size > 10
    merged = merge_coplanar(pts, nb.indices, lab, regions, math.cos(math.radians(10)), 0.015)
    merged, regions2 = fit_regions(pts, merged, 3)
    assert regions2.sizes.size < regions.sizes.size
    assert regions2.sizes[0] > regions.sizes[0]
    assert regions2.sizes[0] > 0.8 * np.sum(lab >= 0)


def test_region_numbering_is_by_size_and_planes_are_fitted():
    pts = _fold()
    keep = (pts[:, 2] == 0) | (pts[:, 2] < 0.5)  # the vertical face is cut to half
    pts = pts[keep]
    nb, lab = _grow(pts)
    lab, regions = fit_regions(pts, lab, 50)
    assert regions.sizes[0] >= regions.sizes[1]
    assert np.all(regions.rms < 1e-3)
