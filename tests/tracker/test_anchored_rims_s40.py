"""Anchored rims (session 40): a geometric rim with a brightness sign is moved to where its field is zero, absolutely,
but only in updates where the points no refiner moves anchor the pose; its offset moves the edge-offset learner's base,
and a restore writes it back."""

import numpy as np
from test_edge_offsets import DOWN, K, grid_field, grid_map

from evpose.core.contour_map import ContourMap
from evpose.tracker.anchored_rims import AnchoredRimConfig, AnchoredRims, rim_points
from evpose.tracker.edge_offsets import EdgeOffsetConfig, EdgeOffsetLearner

RIM = 21
"""The grid's first x line (its first 21 points): made a rim, mapped 1 cm off."""


def rim_map() -> ContourMap:
    g = grid_map(shift_first_m=0.01)
    sign = np.zeros(len(g), np.int8)
    sign[:RIM] = 1
    curv = np.full(len(g), 0.05, np.float32)  # geometric: above the painted refiner's 0.005
    return ContourMap.from_points(g.points, edge_normal=g.edge_normal, plane_normal=g.plane_normal, curvature=curv,
                                  brightness_sign=sign)


def setup(share: float):
    cmap = rim_map()
    tangents = np.cross(cmap.plane_normal, cmap.edge_normal)
    learner = EdgeOffsetLearner(EdgeOffsetConfig(gain=0.0), cmap.points, cmap.edge_normal, tangents)
    rims = AnchoredRims(AnchoredRimConfig(anchor_share=share, gain=0.3, step_clip_px=0.5), cmap, 0.005, learner, None)
    return cmap, learner, rims


def test_only_the_geometric_rims_with_a_brightness_sign_are_rims():
    cmap = rim_map()
    assert np.array_equal(np.flatnonzero(rim_points(cmap, 0.005)), np.arange(RIM))
    assert not rim_points(cmap, 1.0).any()  # with every point "painted" there is no geometric rim


def test_a_rim_moves_onto_its_field_while_anchored_and_the_learner_keeps_it():
    cmap, learner, rims = setup(0.5)
    pts = np.array(cmap.points)
    fld = grid_field()
    used = np.arange(len(cmap))
    for _ in range(60):
        learner.update(pts, used, fld, DOWN, K)
        rims.update(pts, used, fld, DOWN, K)
    assert rims.last_share > 0.5
    # Most of the 1 cm map error learned absolutely (the last 0.2 px, where this smooth bowl's slope is below the
    # refiner's ``min_gradient``, stays).
    assert np.all((rims.offsets < -0.005) & (rims.offsets > -0.011))
    assert np.allclose(pts[:RIM, 0], cmap.points[:RIM, 0] + rims.offsets)
    # The edge-offset learner writes its base (now with the rim's offset) plus its own offsets.
    learner.apply(pts)
    assert np.allclose(pts[:RIM, 0], cmap.points[:RIM, 0] + rims.offsets)
    assert np.array_equal(pts[RIM:], cmap.points[RIM:])  # the anchors stay (the learner's gain is 0)


def test_nothing_moves_while_the_rims_dominate_the_registered_points():
    cmap, learner, rims = setup(0.5)
    pts = np.array(cmap.points)
    used = np.arange(2 * RIM)  # the rim and one other line: anchors 50 % ...
    assert rims.update(pts, used[: RIM + 10], grid_field(), DOWN, K) == 0  # ... 10 of 31: below the share
    assert rims.last_share < 0.5 and np.all(rims.offsets == 0) and np.array_equal(pts, cmap.points)
    assert rims.update(pts, used, grid_field(), DOWN, K) > 0  # 21 of 42 anchor: at the share, it refines


def test_restore_writes_the_offsets_back_into_the_learners_base():
    cmap, learner, rims = setup(0.5)
    pts = np.array(cmap.points)
    state = rims.snapshot()
    for _ in range(5):
        rims.update(pts, np.arange(len(cmap)), grid_field(), DOWN, K)
    moved = rims.snapshot()
    rims.restore(state)
    learner.apply(pts)
    assert np.array_equal(pts, cmap.points)
    rims.restore(moved)
    learner.apply(pts)
    assert np.allclose(pts[:RIM, 0] - cmap.points[:RIM, 0], moved[0])
