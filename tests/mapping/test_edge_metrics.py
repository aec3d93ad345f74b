"""contour_precision_recall: distances to segments, visible length, coverage."""

from __future__ import annotations

import numpy as np

from evpose.mapping.edge_metrics import contour_precision_recall, edge_faces, point_segment_distances, sample_segments

SEG = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]])


def test_point_segment_distance_uses_the_closest_point_and_clamps_to_the_ends():
    pts = np.array([[0.5, 0.3, 0.0], [2.0, 0.0, 0.0], [-1.0, 0.0, 1.0]])
    d = point_segment_distances(pts, SEG)
    assert np.allclose(d, [0.3, 1.0, np.sqrt(2.0)])


def test_points_on_the_edge_give_full_precision_and_recall():
    pts = np.stack([np.linspace(0, 1, 101), np.zeros(101), np.zeros(101)], axis=1)
    m = contour_precision_recall(pts, SEG)
    assert m["precision"] == 1.0 and m["recall"] == 1.0
    assert np.isclose(m["edge_length_m"], 1.0)


def test_half_covered_edge_has_half_recall_and_far_points_lower_precision():
    near = np.stack([np.linspace(0, 0.5, 51), np.full(51, 0.01), np.zeros(51)], axis=1)
    far = np.array([[0.5, 1.0, 0.0]] * 49)
    m = contour_precision_recall(np.vstack([near, far]), SEG, tolerance_m=0.02)
    assert np.isclose(m["precision"], 51 / 100)
    assert abs(m["recall"] - 0.52) < 0.03  # 0..0.5 plus the 2 cm reach beyond its end


def test_recall_counts_only_the_part_of_the_edge_the_scan_saw():
    cloud = np.stack([np.linspace(0, 0.4, 50), np.zeros(50), np.full(50, 0.01)], axis=1)
    covered = np.stack([np.linspace(0, 0.4, 41), np.zeros(41), np.zeros(41)], axis=1)
    m = contour_precision_recall(covered, SEG, cloud=cloud, visible_radius_m=0.05)
    assert abs(m["visible_length_m"] - 0.45) < 0.01
    # Visible: 0..0.45 (cloud to 0.4 plus the 5 cm radius); covered: 0..0.42.
    assert abs(m["recall"] - 0.42 / 0.45) < 0.02


def test_empty_contour_scores_zero():
    m = contour_precision_recall(np.zeros((0, 3)), SEG)
    assert m["precision"] == 0.0 and m["recall"] == 0.0 and m["n_points"] == 0


def test_segment_samples_carry_the_segment_length():
    pts, w = sample_segments(np.array([[[0, 0, 0], [0, 0, 0.3]], [[1, 1, 1], [1, 1, 1]]], float), 0.1)
    assert pts.shape == (3, 3) and np.isclose(w.sum(), 0.3)


def _unit_box_edges():
    from evpose.sim.scenes import box_edges

    return box_edges((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))


def test_edge_faces_finds_the_two_faces_meeting_at_each_box_edge():
    seg = _unit_box_edges()
    faces = edge_faces(seg)
    for j in range(seg.shape[0]):
        e = seg[j, 1] - seg[j, 0]
        e /= np.linalg.norm(e)
        for f in range(2):
            d, n = faces[j, f]
            assert np.isclose(np.linalg.norm(d), 1.0) and abs(d @ e) < 1e-9 and abs(n @ e) < 1e-9
        # The two faces are the box's two planes through the edge: perpendicular normals.
        assert abs(faces[j, 0, 1] @ faces[j, 1, 1]) < 1e-9


def test_edge_faces_leave_a_polyline_without_faces():
    line = np.array([[[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [1, 1, 0]]], float)
    assert not edge_faces(line).any()


def test_face_visibility_needs_points_on_both_faces_not_just_any_surface():
    # Edge along x at the corner y=0, z=0 of faces z=0 (y>0) and y=0 (z>0).
    seg = np.array([[[0, 0, 0], [1, 0, 0], ], [[0, 0, 0], [0, 1, 0]], [[0, 0, 0], [0, 0, 1]],
                    [[1, 0, 0], [1, 1, 0]], [[1, 0, 0], [1, 0, 1]]], float)
    faces = edge_faces(seg)[:1]
    xs = np.linspace(0.0, 1.0, 101)
    floor = np.stack([xs, np.full(101, 0.03), np.zeros(101)], axis=1)
    wall = np.stack([xs, np.zeros(101), np.full(101, 0.03)], axis=1)
    other = np.stack([xs, np.full(101, 0.03), np.full(101, 0.03)], axis=1)  # a third surface, on neither plane
    contour = np.stack([xs, np.zeros(101), np.zeros(101)], axis=1)
    one_face = contour_precision_recall(contour, seg[:1], cloud=np.vstack([floor, other]), visible_radius_m=0.1, faces=faces)
    both = contour_precision_recall(contour, seg[:1], cloud=np.vstack([floor, wall]), visible_radius_m=0.1, faces=faces)
    old = contour_precision_recall(contour, seg[:1], cloud=np.vstack([floor, other]), visible_radius_m=0.1)
    assert one_face["visible_length_m"] == 0.0
    assert both["visible_length_m"] > 0.99 and both["recall"] == 1.0
    assert old["visible_length_m"] > 0.99  # the old rule takes any surface
