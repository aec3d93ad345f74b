"""The registration-bias diagnostic's perfect map: points along the true edges at a fixed spacing."""

import numpy as np

from evpose.bench.registration_bias import true_edge_points


def test_true_edge_points_cover_each_segment_end_to_end_at_the_spacing():
    segs = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[0.0, 0.0, 1.0], [0.0, 0.02, 1.0]]])
    pts = true_edge_points(segs, step_m=0.1)
    first = pts[:11]
    assert np.allclose(first[0], segs[0, 0]) and np.allclose(first[-1], segs[0, 1])
    assert np.allclose(np.diff(first[:, 0]), 0.1)
    assert pts.shape == (11 + 2, 3)  # a segment shorter than the spacing keeps both ends
    assert true_edge_points(np.zeros((0, 2, 3))).shape == (0, 3)


def _ramp_field(min_col: float):
    """A TDF reading |column - min_col| / 10 (its minimum on column ``min_col``), over the whole 100 x 40 image."""
    from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField

    fld = TemporalDistanceField(DistanceFieldConfig(blur_px=0), 100, 40)
    fld.value[0] = (np.abs(np.arange(100) - min_col) / 10.0).astype(np.float32)[None, :]
    fld.box[:] = (0, 40, 0, 100)
    fld.slots_ready = (0,)
    return fld


def test_minimum_offsets_give_the_signed_distance_to_the_field_minimum_along_the_normal():
    from evpose.bench.registration_bias import minimum_offsets

    fld = _ramp_field(50)
    uv = np.array([[48.5, 20.0], [52.0, 20.0], [48.5, 20.0]])
    normals = np.array([[1.0, 0.0], [1.0, 0.0], [-1.0, 0.0]])
    off = minimum_offsets(fld, uv, normals)
    assert np.allclose(off, [1.5, -2.0, -1.5], atol=1e-9)


def test_minimum_offsets_are_nan_without_a_low_minimum_or_when_the_line_leaves_the_field():
    from evpose.bench.registration_bias import minimum_offsets

    fld = _ramp_field(50)
    fld.value[0] += 0.8  # the minimum now reads 0.8, above the 0.7 a minimum must stay below
    assert np.isnan(minimum_offsets(fld, np.array([[50.0, 20.0]]), np.array([[1.0, 0.0]]))).all()
    fld = _ramp_field(50)
    assert np.isnan(minimum_offsets(fld, np.array([[97.0, 20.0]]), np.array([[1.0, 0.0]]))).all()  # +4 px is outside


def test_true_edge_samples_give_each_point_its_segment_direction_and_index():
    from evpose.bench.registration_bias import true_edge_samples

    segs = np.array([[[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]], [[1.0, 0.0, 0.0], [1.0, 0.0, -0.5]]])
    pts, dirs, seg = true_edge_samples(segs, step_m=0.5)
    assert pts.shape == (5 + 2, 3) and seg.tolist() == [0] * 5 + [1] * 2
    assert np.allclose(dirs[:5], [0.0, 1.0, 0.0]) and np.allclose(dirs[5:], [0.0, 0.0, -1.0])


def test_true_edge_map_gives_the_tracker_each_segment_direction():
    from evpose.bench.registration_bias import true_edge_map

    segs = np.array([[[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]], [[1.0, 0.0, 0.0], [1.0, 0.0, -0.5]]])
    cmap, dirs, _ = true_edge_map(segs, step_m=0.5)
    tangent = np.cross(cmap.plane_normal, cmap.edge_normal)
    assert np.allclose(tangent, dirs, atol=1e-6) and np.allclose(np.linalg.norm(cmap.edge_normal, axis=1), 1.0, atol=1e-6)


def test_distance_to_segments_is_the_exact_distance_to_the_nearest_segment_clamped_at_its_ends():
    from evpose.bench.registration_bias import distance_to_segments

    segs = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]])
    pts = np.array([[0.5, 0.1, 0.0], [0.5, 0.8, 0.0], [2.0, 0.0, 0.0], [-1.0, 1.0, 1.0]])
    d, k = distance_to_segments(pts, segs)
    assert np.allclose(d, [0.1, 0.2, 1.0, np.sqrt(2.0)])
    assert list(k) == [0, 1, 0, 1]


def test_map_accuracy_counts_points_off_by_more_than_two_centimetres_by_nearest_segment_kind():
    from evpose.bench.registration_bias import map_accuracy
    from evpose.core.contour_map import ContourMap

    segs = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]])  # the second painted
    cmap = ContourMap.from_points(np.array([[0.2, 0.001, 0.0], [0.4, 0.03, 0.0], [0.6, 0.97, 0.0], [0.8, 1.005, 0.0]]))
    acc = map_accuracy(cmap, segs, n_painted_segments=1)
    assert acc["map_points"] == 4 and acc["map_misplaced_share"] == 0.5
    assert acc["map_misplaced_geometric"] == 1 and acc["map_misplaced_painted"] == 1
    assert np.isclose(acc["map_error_median_mm"], 17.5)
