"""The numba rotation-vector matrices equal scipy's ``Rotation.from_rotvec(...).as_matrix()`` bit for bit."""
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.geometry import rotvec_matrices


def test_rotvec_matrices_equal_scipy_over_every_angle_range():
    rng = np.random.default_rng(0)
    for scale in (0.0, 1e-7, 1e-4, 5e-4, 1e-3, 2e-3, 1e-2, 0.1, 1.0, 3.0):
        rv = rng.normal(size=(3000, 3)) * scale
        np.testing.assert_array_equal(rotvec_matrices(rv), Rotation.from_rotvec(rv).as_matrix())


def test_rotvec_matrices_at_the_series_switch_and_for_one_vector():
    rv = np.array([[1e-3, 0.0, 0.0], [0.0, np.nextafter(1e-3, 1.0), 0.0], [0.0, 0.0, np.pi]])
    np.testing.assert_array_equal(rotvec_matrices(rv), Rotation.from_rotvec(rv).as_matrix())
    np.testing.assert_array_equal(rotvec_matrices(np.array([0.3, -0.2, 0.1]))[0], Rotation.from_rotvec([0.3, -0.2, 0.1]).as_matrix())
