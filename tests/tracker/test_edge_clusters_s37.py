"""Per-edge shared offsets in the events' normal equations (session 37, :mod:`evpose.tracker.edge_clusters`): which
map points form one edge, the generalised least squares correction, the edge-level Huber weights; off by default."""

import numpy as np

from evpose.tracker.config import TrackerConfig
from evpose.tracker.edge_clusters import edge_cluster_ids, edge_weights, shared_offset_correction


def test_points_of_one_region_direction_and_cell_form_one_edge():
    points = np.array([[0.1, 0.1, 0.0], [0.3, 0.1, 0.0], [0.1, 0.1, 0.0], [0.3, 0.2, 0.0], [0.7, 0.1, 0.0], [0.2, 0.2, 0.0]])
    normals = np.array([[1.0, 0.1, 0], [0.9, -0.2, 0], [0, 1.0, 0], [1.0, 0, 0], [1.0, 0, 0], [0, 0, 0]])
    region = np.array([3, 3, 3, 4, 3, 3])
    ids = edge_cluster_ids(points, normals, region, 0.5)
    assert ids[0] == ids[1]  # same region, both normals along +x, one 0.5 m cube
    assert len({ids[0], ids[2], ids[3], ids[4], ids[5]}) == 5  # other direction, region, cube; unknown normal alone


def test_the_correction_is_the_generalised_least_squares_of_edges_sharing_an_offset():
    rng = np.random.default_rng(1)
    n = 12
    J = rng.normal(size=(n, 6))
    r = rng.normal(size=n)
    cluster = np.array([0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 2], np.int64)  # each event its own point here
    edge_var, event_var = 0.01, 0.09
    H, b = J.T @ J, J.T @ r
    shared_offset_correction(cluster, np.ones(n), r.copy(), J.copy(), edge_var, event_var, H, b)
    omega = np.eye(n)  # event_var times the inverse covariance sigma^2 I + s_e^2 1 1^T per edge
    for c in range(3):
        idx = np.flatnonzero(cluster == c)
        cov = event_var * np.eye(idx.size) + edge_var * np.ones((idx.size, idx.size))
        omega[np.ix_(idx, idx)] = event_var * np.linalg.inv(cov)
    assert np.allclose(H, J.T @ omega @ J)
    assert np.allclose(b, J.T @ omega @ r)
    assert np.all(np.linalg.eigvalsh(H) > 0)  # the information only shrinks: never indefinite from a definite start


def test_an_edge_whose_mean_residual_exceeds_the_huber_scale_is_weighed_down():
    cluster = np.array([0, 0, 1, 1], np.int64)
    sw = np.array([2.0, 2.0, 1.0, 1.0])
    swr = np.array([0.6, 0.6, 0.05, -0.15])  # edge 0 mean 0.3 px, edge 1 mean -0.05 px
    pscale = np.empty(4)
    edge_weights(cluster, sw, swr, pscale, 0.15)
    assert np.allclose(pscale, [0.5, 0.5, 1.0, 1.0])


def test_off_by_default():
    c = TrackerConfig().event_registration.edge_clusters
    assert c.edge_sigma_px == 0.0 and c.edge_huber_px == 0.0
