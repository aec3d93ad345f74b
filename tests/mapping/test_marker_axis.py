"""A region's marker axis: the common direction of its fitted straight edges modulo quarter turns."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.mapping.marker_axis import fitted_lines, marker_axis


def _normal(deg: float) -> np.ndarray:
    return np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg))])


def test_square_lines_give_their_common_direction_weighted_by_length():
    # Sides of a marker turned by 2 degrees, measured with tilts of +-1 degree; the long sides weigh most.
    lines = [(_normal(2.0 + 0.2), 2.0), (_normal(92.0 - 0.2), 2.0), (_normal(182.0 + 1.0), 0.4), (_normal(272.0 - 1.0), 0.4)]
    assert np.degrees(marker_axis(lines)) == pytest.approx(2.0, abs=0.05)


def test_lines_not_square_to_one_another_give_no_axis():
    lines = [(_normal(0.0), 1.0), (_normal(30.0), 1.0), (_normal(60.0), 1.0), (_normal(75.0), 1.0)]
    assert marker_axis(lines) is None


def test_too_few_lines_give_no_axis():
    assert marker_axis([(_normal(0.0), 1.0), (_normal(90.0), 1.0)]) is None


def test_fitted_lines_reports_each_run_of_shared_normals_with_its_length():
    p = np.stack([np.arange(0.0, 1.0, 0.01), np.zeros(100)], axis=1)
    n = np.tile([0.0, 1.0], (100, 1))
    n[60:] = [0.1, 0.995]
    on = np.ones(100, bool)
    on[40:45] = False
    lines = fitted_lines(p, n, on)
    assert [round(length, 2) for _, length in lines] == [0.39, 0.14, 0.39]


def test_a_sparse_painted_rectangle_comes_out_square_and_closer_to_its_true_edges():
    from evpose.mapping import MapBuildConfig, build_contour_map
    from evpose.mapping.edge_metrics import point_segment_distances
    from evpose.mapping.synthetic import painted_plane

    # 100 points/m^2 like the simulator's scans: a free fit tilts each side by up to a degree or two.
    scan = painted_plane(size=3.0, panel=(0.8, 0.7, 1.4, 1.2), density=100.0, noise_m=0.005, intensity_noise=0.03, seed=3)
    rms, square = [], []
    for kw in ({}, {"albedo_marker_snap_deg": 12.0, "albedo_corner_reach_m": 0.3}):
        cm = build_contour_map(scan.points, intensity=scan.intensity, config=MapBuildConfig(**kw))
        sel = cm.brightness_sign != 0
        ang = np.degrees(np.arctan2(cm.edge_normal[sel, 1], cm.edge_normal[sel, 0])) % 90.0
        ang = np.where(ang > 45.0, ang - 90.0, ang)
        square.append(float(np.mean(np.abs(ang - np.median(ang)) < 0.01)))
        rms.append(float(np.sqrt(np.mean(point_segment_distances(cm.points[sel], scan.edges) ** 2))))
    assert square[1] >= 0.95 > square[0]
    assert rms[1] < 0.7 * rms[0]
