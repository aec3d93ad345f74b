"""contour_precision_recall: distances to segments, visible length, coverage."""

from __future__ import annotations

import numpy as np

from evpose.mapping.edge_metrics import contour_precision_recall, point_segment_distances, sample_segments

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
