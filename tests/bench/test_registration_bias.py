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
