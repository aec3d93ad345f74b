"""build_contour_map on synthetic scans with known edges: accuracy, rim suppression, attributes, determinism, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.mapping import MapBuildConfig, MapBuildError, build_contour_map
from evpose.mapping.edge_metrics import contour_precision_recall, point_segment_distances
from evpose.mapping.synthetic import Box, boxes_on_ground, cabinet_before_wall, wall_with_window


def test_boxes_on_ground_meet_precision_and_recall_targets(boxes_scan, boxes_map):
    m = contour_precision_recall(boxes_map.points, boxes_scan.edges, tolerance_m=0.02, cloud=boxes_scan.points)
    assert m["precision"] >= 0.95
    assert m["recall"] >= 0.90


def test_ground_rim_where_the_scan_stops_yields_no_contour(boxes_scan, boxes_map):
    # The ground is 6 x 6 m; its border is the scan's extent, not an object edge.
    near_rim = np.abs(boxes_map.points[:, :2]).max(axis=1) > 2.8
    assert not near_rim.any()


def test_single_plane_gives_only_its_true_border(window_scan):
    cmap = build_contour_map(window_scan.points, intensity=window_scan.intensity)
    m = contour_precision_recall(cmap.points, window_scan.edges, cloud=window_scan.points)
    assert m["precision"] >= 0.95 and m["recall"] >= 0.90
    p = cmap.points
    on_rim = (p[:, 0] < 0.1) | (p[:, 0] > 3.9) | (p[:, 2] < 0.1) | (p[:, 2] > 2.9)
    assert not on_rim.any()


def test_a_bounded_plane_alone_has_no_contour_and_is_rejected():
    scan = wall_with_window(window=(1.5, 1.0, 0.0, 0.0), noise_m=0.002, seed=3)
    with pytest.raises(MapBuildError, match="no object contour"):
        build_contour_map(scan.points)


@pytest.mark.parametrize("noise_m", [0.0, 0.01])
def test_accuracy_holds_across_range_noise_levels(noise_m):
    boxes = (Box((-0.6, -0.5), (0.8, 0.7, 0.5)), Box((0.7, 0.6), (0.7, 0.9, 0.6), yaw_deg=25.0))
    scan = boxes_on_ground(boxes, half_extent=1.6, noise_m=noise_m, seed=4)
    cmap = build_contour_map(scan.points)
    m = contour_precision_recall(cmap.points, scan.edges, cloud=scan.points)
    assert m["precision"] >= 0.95
    assert m["recall"] >= 0.90


def test_edge_normals_point_out_of_the_region_and_top_normals_up(boxes_scan, boxes_map):
    # Points on the top face (z = 0.5) of the first box, centred at (-1.2, -0.8).
    top = (np.abs(boxes_map.points[:, 2] - 0.5) < 0.01) & (np.abs(boxes_map.plane_normal[:, 2]) > 0.9)
    top &= np.linalg.norm(boxes_map.points[:, :2] - [-1.2, -0.8], axis=1) < 0.8
    assert top.sum() > 100
    away = boxes_map.points[top, :2] - [-1.2, -0.8]
    assert np.mean(np.einsum("nd,nd->n", away, boxes_map.edge_normal[top, :2]) > 0) > 0.95
    assert np.all(boxes_map.plane_normal[top, 2] > 0.9)
    assert np.allclose(np.linalg.norm(boxes_map.edge_normal, axis=1), 1.0, atol=1e-5)
    assert np.allclose(np.einsum("nd,nd->n", boxes_map.edge_normal, boxes_map.plane_normal), 0.0, atol=1e-4)


def test_brightness_sign_follows_the_albedo_across_the_edge(boxes_map):
    def top_of(center, z):
        sel = (np.abs(boxes_map.points[:, 2] - z) < 0.01) & (np.abs(boxes_map.plane_normal[:, 2]) > 0.9)
        return sel & (np.linalg.norm(boxes_map.points[:, :2] - center, axis=1) < 0.8)

    bright_top = boxes_map.brightness_sign[top_of([-1.2, -0.8], 0.5)]  # top 0.8, sides 0.55, ground 0.35
    dark_top = boxes_map.brightness_sign[top_of([1.0, 0.9], 0.8)]  # top 0.1, sides 0.2, ground 0.35
    assert np.mean(bright_top == -1) > 0.9  # darker beyond the edge
    assert np.mean(dark_top == 1) > 0.9  # brighter beyond the edge


def test_map_without_intensity_has_unknown_brightness(boxes_scan):
    small = boxes_on_ground((Box((0.0, 0.0), (0.8, 0.8, 0.4)),), half_extent=1.2, seed=5)
    cmap = build_contour_map(small.points)
    assert len(cmap) > 0 and np.all(cmap.brightness_sign == 0)


def test_cabinet_a_few_cm_before_a_wall_keeps_its_back_edges_apart_from_the_wall():
    # The cabinet's back face 6 cm in front of the wall, both sampled (400 points/m^2, 5 mm
    # noise). Plain PCA normals and a 4.5 cm growth offset (the builder before one-sided
    # normals, no second pass over the leftover points) merge the two layers; measured over
    # seeds 0-3: precision 0.75 -> 0.89, recall 0.66 -> 0.96.
    new, old = [], []
    for seed in (0, 1):
        scan = cabinet_before_wall(gap_m=0.06, density=400.0, seed=seed)
        for out, cfg in ((new, MapBuildConfig()), (old, MapBuildConfig(robust_normals=False, grow_offset_m=0.045, leftover_regions=False))):
            cmap = build_contour_map(scan.points, intensity=scan.intensity, config=cfg)
            m = contour_precision_recall(cmap.points, scan.edges, cloud=scan.points)
            out.append((m["precision"], m["recall"]))
    precision, recall = np.mean(new, axis=0)
    assert precision >= 0.85 and recall >= 0.9
    assert recall > np.mean(old, axis=0)[1] + 0.15


def test_build_is_bit_identical_for_the_same_input():
    scan = boxes_on_ground((Box((0.0, 0.0), (0.8, 0.8, 0.4), yaw_deg=10.0),), half_extent=1.2, seed=6)
    a = build_contour_map(scan.points, intensity=scan.intensity)
    b = build_contour_map(scan.points.copy(), intensity=scan.intensity.copy())
    for name in ("points", "edge_normal", "plane_normal", "region_id", "curvature", "brightness_sign"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_voxel_downsampling_keeps_the_edges():
    scan = boxes_on_ground((Box((0.0, 0.0), (0.8, 0.8, 0.4)),), half_extent=1.2, density=6000, seed=7)
    cmap = build_contour_map(scan.points, config=MapBuildConfig(voxel_m=0.02))
    d = point_segment_distances(cmap.points, scan.edges)
    assert np.mean(d < 0.02) > 0.95


def test_empty_cloud_is_rejected():
    with pytest.raises(MapBuildError, match="empty"):
        build_contour_map(np.zeros((0, 3)))


def test_nan_coordinate_is_rejected_with_its_index():
    pts = np.random.default_rng(0).random((100, 3))
    pts[42, 1] = np.nan
    with pytest.raises(MapBuildError, match="point 42"):
        build_contour_map(pts)


def test_wrong_shape_and_intensity_length_are_rejected():
    with pytest.raises(MapBuildError, match="shape"):
        build_contour_map(np.zeros((10, 2)))
    with pytest.raises(MapBuildError, match="intensity"):
        build_contour_map(np.random.default_rng(0).random((50, 3)), intensity=np.zeros(49))
