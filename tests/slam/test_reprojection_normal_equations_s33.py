"""The shared reprojection normal equations: zero gradient at the truth, a step that recovers a perturbed pose."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.reprojection_normal_equations import left_gauss_newton_step, refine_with_prior, reprojection_normal_equations

K = np.array([[250.0, 0, 173], [0, 250.0, 130], [0, 0, 1]])


def _points_and_pixels(T_cw, n=25, seed=0):
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-1, 1, n), rng.uniform(-0.8, 0.8, n), rng.uniform(3, 6, n)]
    Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
    return X, Xc[:, :2] / Xc[:, 2:] * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]


def test_the_gradient_vanishes_at_the_pose_that_saw_the_pixels():
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.01, -0.02, 0.03]).as_matrix()
    T[:3, 3] = [0.1, -0.05, 0.2]
    X, uv = _points_and_pixels(T)
    H, g = reprojection_normal_equations(T, X, uv, K, huber_px=2.0)
    assert H.shape == (6, 6) and g.shape == (6,)
    assert np.allclose(H, H.T) and np.all(np.linalg.eigvalsh(H) > 0)
    assert np.abs(g).max() < 1e-9


def test_a_few_steps_bring_a_perturbed_pose_back_and_report_convergence():
    truth = np.eye(4)
    X, uv = _points_and_pixels(truth)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.0, 0.01, 0.0]).as_matrix()
    T[:3, 3] = [0.03, 0.0, -0.02]
    converged = False
    for _ in range(10):
        H, g = reprojection_normal_equations(T, X, uv, K, huber_px=100.0)
        T, converged = left_gauss_newton_step(T, H, g)
        if converged:
            break
    assert converged
    assert np.abs(T - truth).max() < 1e-9


def test_fewer_than_three_points_in_front_give_no_equations_and_a_singular_system_no_step():
    T = np.eye(4)
    X, uv = _points_and_pixels(T, n=5)
    X[2:, 2] = -1.0  # three of five behind the camera
    assert reprojection_normal_equations(T, X, uv, K, huber_px=2.0) is None
    assert left_gauss_newton_step(T, np.zeros((6, 6)), np.ones(6)) is None


def test_the_refinement_loop_calls_the_prior_at_each_pose_and_recovers_the_truth_without_one():
    truth = np.eye(4)
    X, uv = _points_and_pixels(truth)
    start = np.eye(4)
    start[:3, 3] = [0.02, -0.01, 0.03]
    seen = []
    out = refine_with_prior(K, X, uv, start, lambda T, H, g: seen.append(T.copy()), huber_px=100.0)
    assert np.abs(out - truth).max() < 1e-9
    assert 1 <= len(seen) <= 8 and np.array_equal(seen[0], start)
    # A prior pulling the translation to 1 m along x moves the estimate towards it.
    def pull(T, H, g):
        H[3:, 3:] += np.eye(3) * 1e6
        g[3:] += (T[:3, 3] - [1.0, 0.0, 0.0]) * 1e6

    pulled = refine_with_prior(K, X, uv, start, pull, huber_px=100.0)
    assert pulled[0, 3] > 0.1
