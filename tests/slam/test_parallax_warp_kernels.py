"""H5's projection of moved points in numba equals the numpy einsum it replaced, bit for bit."""
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.parallax_warp import project_moved

K = np.array([[190.0, 0.0, 173.0], [0.0, 190.0, 130.0], [0.0, 0.0, 1.0]])


def _project_moved_ref(K, X, xis):
    R = Rotation.from_rotvec(xis[:, :3]).as_matrix()
    q = np.einsum("ij,mkj,mnk->mni", K, R, X[None] - xis[:, None, 3:])
    return q[..., :2] / q[..., 2:3]


def test_project_moved_equals_einsum():
    rng = np.random.default_rng(0)
    for _ in range(200):
        X = rng.normal(size=(int(rng.integers(1, 60)), 3)) * [1.0, 1.0, 0.2] + [0.0, 0.0, rng.uniform(0.5, 8.0)]
        xis = rng.normal(size=(int(rng.integers(1, 50)), 6)) * rng.choice([0.0, 1e-4, 1e-2, 1.0])
        np.testing.assert_array_equal(project_moved(K, X, xis), _project_moved_ref(K, X, xis))


def test_project_moved_behind_the_camera_matches_numpy_inf_and_nan():
    X = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    xis = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], np.zeros(6)])
    with np.errstate(divide="ignore", invalid="ignore"):
        np.testing.assert_array_equal(project_moved(K, X, xis), _project_moved_ref(K, X, xis))
