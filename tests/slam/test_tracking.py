"""Tests of evpose/slam/tracking.py: the pose from 2D-3D pairs."""

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.tracking import estimate_pose
from evpose.slam.tracking_config import TrackingConfig

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _pairs(n=60, seed=0):
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2, 2, n), rng.uniform(-1.5, 1.5, n), rng.uniform(3, 6, n)]
    T_wc = np.eye(4)
    T_wc[:3, 3] = [0.1, -0.05, 0.2]
    T_cw = invert_pose(T_wc)
    Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
    return X, Xc[:, :2] / Xc[:, 2:3] @ K[:2, :2].T + K[:2, 2], T_wc


def test_pose_from_exact_pairs_is_recovered_from_a_nearby_guess():
    X, uv, T_wc = _pairs()
    est = estimate_pose(K, X, uv, np.eye(4), TrackingConfig())
    assert est.ok and est.inliers.all()
    assert np.allclose(est.T_wc, T_wc, atol=1e-6)


def test_an_opencv_solver_assertion_is_a_failed_estimate_with_a_reason(monkeypatch):
    X, uv, _ = _pairs()

    def raising(*args, **kwargs):
        raise cv2.error("OpenCV(5.1) solvePoly: assertion failed")

    monkeypatch.setattr(cv2, "solvePnPRansac", raising)
    est = estimate_pose(K, X, uv, np.eye(4), TrackingConfig())
    assert not est.ok and est.reason.startswith("PnP failed") and "assertion" in est.reason
