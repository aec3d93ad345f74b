"""merge_double_contours: one copy per edge across regions, never thinning a region's own contour."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from evpose.mapping import MapBuildConfig, build_contour_map
from evpose.mapping.dedup import merge_double_contours
from evpose.mapping.edge_metrics import contour_precision_recall


def _line(x, n=50, z=0.0):
    t = np.arange(n) * 0.01
    return np.stack([np.full(n, x), t, np.full(n, z)], axis=1)


def test_two_copies_of_one_edge_merge_halfway_and_a_distant_contour_stays():
    pts = np.concatenate([_line(0.0), _line(0.012), _line(0.08)])
    region = np.repeat([0, 1, 1], 50)
    priority = np.repeat([10.0, 5.0, 5.0], 50)
    keep, merged = merge_double_contours(pts, region, priority, radius=0.02)
    # Region 0 (better supported) keeps its copy; region 1's copy of that edge goes; its far contour stays.
    assert keep[:50].all() and not keep[50:100].any() and keep[100:].all()
    assert np.allclose(merged[:50, 0], 0.006, atol=1e-9)
    assert np.array_equal(merged[100:], pts[100:])


def test_points_of_one_region_never_suppress_each_other():
    pts = _line(0.0, n=200)  # 1 cm spacing, well inside the 2 cm radius
    keep, merged = merge_double_contours(pts, np.zeros(200, np.int64), np.ones(200), radius=0.02)
    assert keep.all() and np.array_equal(merged, pts)


def test_zero_radius_keeps_everything():
    pts = np.concatenate([_line(0.0), _line(0.005)])
    keep, _ = merge_double_contours(pts, np.repeat([0, 1], 50), np.ones(100), radius=0.0)
    assert keep.all()


def test_merging_on_a_box_scan_halves_the_points_and_keeps_the_edges(boxes_scan, boxes_map):
    merged = build_contour_map(boxes_scan.points, intensity=boxes_scan.intensity, config=MapBuildConfig(merge_double_m=0.02))
    before = contour_precision_recall(boxes_map.points, boxes_scan.edges, cloud=boxes_scan.points)
    after = contour_precision_recall(merged.points, boxes_scan.edges, cloud=boxes_scan.points)
    assert len(merged) < 0.7 * len(boxes_map)
    assert after["recall"] >= before["recall"] - 0.01
    # Near-coincident copies from different regions (creases seen from both faces) are gone.
    def cross_pairs(cmap):
        pairs = cKDTree(cmap.points).query_pairs(0.01, output_type="ndarray")
        return int(np.sum(cmap.region_id[pairs[:, 0]] != cmap.region_id[pairs[:, 1]]))

    assert cross_pairs(merged) < 0.1 * cross_pairs(boxes_map)
