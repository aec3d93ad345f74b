"""Crease planes refitted away from the creases, trimmed, optionally squared to the ground (evpose.mapping.crease_planes)."""

from __future__ import annotations

import numpy as np

from evpose.mapping.crease_planes import refit_crease_planes, resnap_creases
from evpose.mapping.region_growing import refit_planes


def _crate_side(seed: int = 0):
    """Ground (region 0), a crate's top at z = 0.4 (region 1) and its side at x = 0 (region 2), 5 mm noise, 100
    points/m^2; the side also holds the top's last points along its rim and the ground's first along its foot, as
    extend_to_planes hands them over."""
    rng = np.random.default_rng(seed)
    def n(k):
        return 0.005 * rng.standard_normal(k)

    ground = np.c_[rng.uniform(0.0, 3.0, 900), rng.uniform(-1.5, 1.5, 900), n(900)]
    top = np.c_[rng.uniform(-0.5, 0.0, 25), rng.uniform(-0.25, 0.25, 25), 0.4 + n(25)]
    side = np.c_[n(20), rng.uniform(-0.25, 0.25, 20), rng.uniform(0.0, 0.4, 20)]
    top_strays = np.c_[rng.uniform(-0.03, -0.01, 6), rng.uniform(-0.25, 0.25, 6), 0.4 + n(6)]
    ground_strays = np.c_[rng.uniform(0.01, 0.03, 6), rng.uniform(-0.25, 0.25, 6), n(6)]
    pts = np.r_[ground, top, side, top_strays, ground_strays]
    labels = np.r_[np.zeros(900, np.int32), np.ones(25, np.int32), np.full(32, 2, np.int32)]
    return pts, labels


def test_a_small_sides_crease_plane_leaves_its_neighbours_strays_out():
    pts, labels = _crate_side()
    reg = refit_planes(pts, labels, 3)
    pairs = np.array([[1, 2], [0, 2]])
    c, n = refit_crease_planes(pts, labels, pairs, reg.centroids, reg.normals, band=0.03)
    rim = np.array([0.0, 0.0, 0.4])
    plain = abs(float((rim - reg.centroids[2]) @ reg.normals[2]))
    refit = abs(float((rim - c[2]) @ n[2]))
    assert plain > 0.004  # the strays tilt the plain fit by ~5 mm at the top rim
    assert refit < 0.5 * plain
    # The ground (900 points) barely changes: its plane through the crate's foot within a millimetre.
    assert abs(float((np.zeros(3) - c[0]) @ n[0]) - float((np.zeros(3) - reg.centroids[0]) @ reg.normals[0])) < 1e-3


def test_square_deg_makes_a_nearly_upright_face_exactly_upright_and_keeps_normal_signs():
    pts, labels = _crate_side(seed=1)
    reg = refit_planes(pts, labels, 3)
    normals = reg.normals * np.array([[1.0], [-1.0], [-1.0]])  # signs as oriented by the builder
    c, n = refit_crease_planes(pts, labels, np.array([[1, 2], [0, 2]]), reg.centroids, normals, band=0.03,
                               square_deg=3.0)
    assert abs(float(n[2] @ n[0])) < 1e-12  # side square to the ground
    assert abs(abs(float(n[1] @ n[0])) - 1.0) < 1e-12  # top parallel to it
    assert np.all(np.einsum("rd,rd->r", n, normals) > 0)


def test_crease_points_move_onto_the_refitted_planes_intersection_within_the_shift_limit():
    plane_c = np.array([[0.0, 0.0, 0.4], [0.002, 0.0, 0.2]])
    plane_n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    before = np.array([[-0.03, 0.1, 0.4], [-0.03, 0.2, 0.4], [-0.5, 0.3, 0.4]])
    snapped = before + [0.03, 0.0, 0.0]
    out = resnap_creases(before, snapped, np.zeros(3, np.int32), np.array([1, -1, 1], np.int32), plane_c, plane_n,
                         max_shift=0.1)
    assert np.allclose(out[0], [0.002, 0.1, 0.4])
    assert np.array_equal(out[1], snapped[1])  # not a crease point
    assert np.array_equal(out[2], snapped[2])  # too far
