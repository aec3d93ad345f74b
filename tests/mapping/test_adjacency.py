"""Snapping contour points onto creases and steps; plane-normal orientation."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping.adjacency import orient_plane_normals, snap_to_intersections, snap_to_steps


def test_contour_point_next_to_a_perpendicular_plane_lands_on_their_crease():
    # Region 0: z = 0.5 (top); region 1: x = 1 (wall). A top contour point 2 cm short of the edge.
    yy, zz = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0, 0.5, 11))
    cloud = np.column_stack([np.ones(yy.size), yy.ravel(), zz.ravel()])
    labels = np.ones(yy.size, np.int32)
    pts = np.array([[0.98, 0.5, 0.5]])
    c = np.array([[0.5, 0.5, 0.5], [1.0, 0.5, 0.25]])
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    out, adj = snap_to_intersections(pts, np.array([0]), labels, cKDTree(cloud), c, n, 0.1, np.radians(30), 0.05)
    assert np.allclose(out[0], [1.0, 0.5, 0.5]) and adj[0] == 1


def test_parallel_neighbour_is_not_a_crease():
    cloud = np.column_stack([np.linspace(1.0, 1.2, 20), np.full(20, 0.5), np.zeros(20)])
    c = np.array([[0.5, 0.5, 0.5], [1.1, 0.5, 0.0]])
    n = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    out, adj = snap_to_intersections(np.array([[0.98, 0.5, 0.5]]), np.array([0]), np.ones(20, np.int32),
                                     cKDTree(cloud), c, n, 1.0, np.radians(30), 1.0)
    assert adj[0] == -1 and np.allclose(out[0], [0.98, 0.5, 0.5])


def test_parallel_surface_closer_than_the_crease_does_not_hide_it():
    # Region 0: a shelf's back face y = 2.95 (contour point 3 cm above its bottom rim); region 2:
    # the wall y = 3.0, 5 cm behind (nearer in the cloud); region 1: the floor z = 0 below.
    xx, zz = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0.0, 0.5, 11))
    wall = np.column_stack([xx.ravel(), np.full(xx.size, 3.0), zz.ravel()])
    xf, yf = np.meshgrid(np.linspace(0, 1, 21), np.linspace(2.0, 2.9, 10))
    floor = np.column_stack([xf.ravel(), yf.ravel(), np.zeros(xf.size)])
    cloud = np.vstack([wall, floor])
    labels = np.concatenate([np.full(wall.shape[0], 2), np.ones(floor.shape[0])]).astype(np.int32)
    c = np.array([[0.5, 2.95, 0.5], [0.5, 2.5, 0.0], [0.5, 3.0, 0.25]])
    n = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
    out, adj = snap_to_intersections(np.array([[0.5, 2.95, 0.03]]), np.array([0]), labels, cKDTree(cloud), c, n,
                                     0.2, np.radians(30), 0.1, k=40)
    assert adj[0] == 1 and np.allclose(out[0], [0.5, 2.95, 0.0])


def test_step_face_points_pull_the_contour_onto_the_face():
    # A 15 cm step: the face at x = 1.5 has unassigned points between z = 0 and 0.15.
    rng = np.random.default_rng(0)
    face = np.column_stack([1.5 + rng.normal(0, 0.003, 40), rng.uniform(0.4, 0.6, 40), rng.uniform(0.02, 0.13, 40)])
    top = np.column_stack([rng.uniform(1.0, 1.5, 200), rng.uniform(0.4, 0.6, 200), np.full(200, 0.15)])
    cloud = np.vstack([face, top])
    labels = np.concatenate([np.full(40, -1), np.zeros(200)]).astype(np.int32)
    pts = np.array([[1.46, 0.5, 0.15]])
    out = snap_to_steps(pts, np.array([[1.0, 0.0, 0.0]]), np.array([0]), np.array([True]), cloud, labels,
                        cKDTree(cloud), np.array([[0.0, 0.0, 1.0]]), radius=0.15, min_offset=0.015,
                        max_offset=0.2, max_shift=0.1)
    assert abs(out[0, 0] - 1.5) < 0.005 and np.allclose(out[0, 1:], pts[0, 1:])


def test_plane_normals_face_up_and_walls_face_the_ground_in_front_of_them():
    rng = np.random.default_rng(1)
    ground = np.column_stack([rng.uniform(-2, 2, 3000), rng.uniform(-2, 0, 3000), np.zeros(3000)])
    wall = np.column_stack([rng.uniform(-2, 2, 1000), np.zeros(1000), rng.uniform(0, 2, 1000)])
    pts = np.vstack([ground, wall])
    labels = np.concatenate([np.zeros(3000), np.ones(1000)]).astype(np.int32)
    normals = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # both initially wrong
    centroids = np.array([ground.mean(axis=0), wall.mean(axis=0)])
    out = orient_plane_normals(normals, centroids, pts, labels, None, None, reach=0.5)
    assert np.allclose(out[0], [0, 0, 1]) and np.allclose(out[1], [0, -1, 0])


def test_rim_in_front_of_a_wall_snaps_to_the_innermost_crease_across_it():
    # Region 0: a sofa's top z = 0.8 ending at y = -2.9; region 1: its back face y = -2.9;
    # region 2: the wall y = -3.0, 10 cm behind. The top's contour point overshoots to
    # y = -2.96, nearer the wall's points than the back's: the nearest-point rule picks the
    # wall; with the outward normal the first crease met going outward - the back - wins.
    xx, zz = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0.0, 1.5, 31))
    wall = np.column_stack([xx.ravel(), np.full(xx.size, -3.0), zz.ravel()])
    xb, zb = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0.0, 0.7, 8))
    back = np.column_stack([xb.ravel(), np.full(xb.size, -2.9), zb.ravel()])
    cloud = np.vstack([wall, back])
    labels = np.concatenate([np.full(wall.shape[0], 2), np.ones(back.shape[0])]).astype(np.int32)
    c = np.array([[0.5, -2.45, 0.8], [0.5, -2.9, 0.35], [0.5, -3.0, 0.75]])
    n = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    pts = np.array([[0.5, -2.96, 0.8]])
    args = (pts, np.array([0]), labels, cKDTree(cloud), c, n, 0.15, np.radians(30), 0.15)
    nearest, adj_nearest = snap_to_intersections(*args)
    inner, adj_inner = snap_to_intersections(*args, outward=np.array([[0.0, -1.0, 0.0]]), across_tol=0.02)
    assert adj_nearest[0] == 2 and np.allclose(nearest[0], [0.5, -3.0, 0.8])
    assert adj_inner[0] == 1 and np.allclose(inner[0], [0.5, -2.9, 0.8])


def test_crease_axes_give_a_wall_the_direction_of_its_creases():
    from evpose.mapping.adjacency import crease_axes

    # Region 0: a wall y = 0 with in-plane axes turned 20 deg from x/z; regions 1 (floor) and 2 (side wall).
    normals = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    t = np.radians(20.0)
    e0 = np.array([np.cos(t), 0.0, np.sin(t)])
    axes = np.zeros((3, 2, 3))
    axes[0] = [e0, np.cross(normals[0], e0)]
    region = np.zeros(60, np.int32)
    crease = np.r_[np.full(40, 1), np.full(20, 2)].astype(np.int32)
    out = crease_axes(region, crease, normals, axes)
    # The floor crease runs along x: +20 deg from the wall's first axis (modulo 90).
    assert abs((np.degrees(out[0]) - 20.0 + 45.0) % 90.0 - 45.0) < 1e-6
    assert np.isnan(out[1]) and np.isnan(out[2])  # no contour points of their own
    assert np.isnan(crease_axes(region, np.full(60, -1, np.int32), normals, axes)[0])
