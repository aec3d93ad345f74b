"""Tests of evpose/slam/tracking.py: the pose from 2D-3D pairs."""

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.tracking import estimate_pose, refine_pose_weighted, track_sigma_px
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


def test_weighted_refinement_with_equal_sigmas_matches_opencv():
    X, uv, _ = _pairs()
    uv = uv + np.random.default_rng(1).normal(0, 0.5, uv.shape)
    rv0, tv0 = np.array([[0.01], [-0.02], [0.01]]), np.array([[-0.1], [0.0], [-0.15]])
    r1, t1 = cv2.solvePnPRefineLM(X.reshape(-1, 1, 3), uv.reshape(-1, 1, 2), K, None, rv0.copy(), tv0.copy())
    r2, t2 = refine_pose_weighted(K, X, uv, rv0, tv0, np.ones(len(X)))
    assert np.allclose(r1, r2, atol=1e-7) and np.allclose(t1, t2, atol=1e-7)


def test_a_large_sigma_lets_the_pose_ignore_a_shifted_point():
    X, uv, T_wc = _pairs(n=20)
    bad = uv.copy()
    bad[0] += 2.0
    sig = np.ones(len(X))
    sig[0] = 1e4
    T_cw = invert_pose(T_wc)
    rv, _ = cv2.Rodrigues(T_cw[:3, :3])
    tv = T_cw[:3, 3].reshape(3, 1) + 0.01
    r_w, t_w = refine_pose_weighted(K, X, bad, rv, tv, sig)
    r_u, t_u = refine_pose_weighted(K, X, bad, rv, tv, np.ones(len(X)))
    err = lambda t: np.linalg.norm(t.ravel() - T_cw[:3, 3])
    assert err(t_w) < 1e-5 < err(t_u)


def test_track_sigma_is_one_pixel_for_fresh_tracks_and_grows_with_the_inverse_mass_and_residuals():
    cfg = TrackingConfig(pnp_track_sigma_gain=3.0, pnp_track_sigma_scale=0.1)
    sig = track_sigma_px([0.0, 0.1, 1e6], [(), (), ()], cfg)
    assert np.allclose(sig, [1.0, np.sqrt(2.5), 2.0], atol=1e-5)
    cfg = TrackingConfig(pnp_residual_sigma_gain=1.0)
    assert np.allclose(track_sigma_px([0.0, 0.0, 0.0], [(), (0.5, 0.2, 0.4), (3.0, 1.0, 2.5)], cfg), [1.0, 1.0, 2.5])
