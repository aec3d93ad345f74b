"""The compiled SE(3) algebra (session 43) equals gtsam's ``Pose3`` ``Expmap`` / ``Logmap`` / ``logmap`` to rounding,
from 1e-9 rad to within 1e-8 of pi (where its logarithm is more exact than gtsam's)."""

import gtsam
import numpy as np

from evpose.core.se3_kernels import between_log, se3_exp, se3_log


def _tangents(rng, n):
    """Random tangent vectors with angles from 1e-9 rad to within 1e-8 of pi (the series, the closed forms and the
    near-pi logarithm)."""
    xi = rng.normal(size=(n, 6))
    w = xi[:, :3] / np.linalg.norm(xi[:, :3], axis=1, keepdims=True)
    xi[:, :3] = w * np.concatenate([10.0 ** rng.uniform(-9, 0.4, n - 20), np.pi - 10.0 ** rng.uniform(-8, -2, 20)])[:, None]
    return xi


def test_se3_exp_log_and_between_equal_gtsam_to_rounding():
    rng = np.random.default_rng(0)
    R, t, out = np.empty((3, 3)), np.empty(3), np.empty(6)
    for xi in _tangents(rng, 400):
        P = gtsam.Pose3.Expmap(xi).matrix()
        se3_exp(xi, R, t)
        assert np.abs(R - P[:3, :3]).max() < 1e-15 * 4 and np.abs(t - P[:3, 3]).max() < 1e-15 * 4 * np.abs(xi).max()
        se3_log(P[:3, :3].copy(), P[:3, 3].copy(), out)
        assert np.abs(out - xi).max() < 1e-14 * np.abs(xi).max()
        if np.linalg.norm(xi[:3]) < 3.0:  # gtsam's own near-pi logarithm is off by up to ~1e-10
            assert np.abs(out - gtsam.Pose3.Logmap(gtsam.Pose3(mat=P))).max() < 1e-14 * np.abs(xi).max()
        A = gtsam.Pose3.Expmap(rng.normal(size=6))
        B = A.compose(gtsam.Pose3(mat=P))
        between_log(A.rotation().matrix(), A.translation(), B.rotation().matrix(), B.translation(), out)
        assert np.abs(out - A.logmap(B)).max() < 1e-8 * np.abs(xi).max()
