"""PCA normals/curvature and deterministic voxel downsampling."""

from __future__ import annotations

import numpy as np

from evpose.mapping.normals import estimate_neighbourhoods, voxel_downsample


def test_plane_normals_are_perpendicular_and_curvature_is_near_zero():
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.random(2000), rng.random(2000), np.zeros(2000)])
    nb = estimate_neighbourhoods(pts, 12)
    assert np.all(np.abs(nb.normals[:, 2]) > 0.999)
    assert nb.curvature.max() < 1e-9
    assert np.array_equal(nb.indices[:, 0], np.arange(2000))
    assert 0.005 < nb.spacing < 0.02


def test_curvature_is_high_at_a_crease_and_low_on_the_faces():
    rng = np.random.default_rng(1)
    a = np.column_stack([rng.random(3000), rng.random(3000), np.zeros(3000)])
    b = np.column_stack([rng.random(3000), np.zeros(3000), rng.random(3000)])
    pts = np.vstack([a, b])
    nb = estimate_neighbourhoods(pts, 16)
    at_crease = (pts[:, 1] < 0.01) & (pts[:, 2] < 0.01)
    on_face = (pts[:, 1] > 0.2) | (pts[:, 2] > 0.2)
    assert np.median(nb.curvature[at_crease]) > 0.05
    assert np.median(nb.curvature[on_face]) < 1e-6


def test_voxel_downsampling_averages_each_voxel_and_its_attributes():
    pts = np.array([[0.01, 0.01, 0.01], [0.03, 0.03, 0.03], [0.51, 0.0, 0.0]])
    inten = np.array([0.2, 0.4, 1.0])
    out, out_i = voxel_downsample(pts, 0.1, inten)
    assert out.shape == (2, 3)
    assert np.allclose(out[0], [0.02, 0.02, 0.02]) and np.isclose(out_i[0], 0.3)
    again = voxel_downsample(pts[::-1].copy(), 0.1, inten[::-1].copy())
    assert np.array_equal(np.sort(out, axis=0), np.sort(again[0], axis=0))


def test_zero_voxel_keeps_the_cloud_untouched():
    pts = np.random.default_rng(2).random((10, 3))
    out, none = voxel_downsample(pts, 0.0, None)
    assert out is pts and none is None
