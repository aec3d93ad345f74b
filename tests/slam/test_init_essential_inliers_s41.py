"""``InitializationConfig.points_essential_inliers``: only the essential matrix's RANSAC inliers become map points."""

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.config import InitializationConfig
from evpose.slam.initialization import initialize_two_view

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _views(seed=0, n=150, noise=0.3):
    """150 points 2.5-7 m away seen from two poses 0.35 m apart, with 0.3 px of track noise."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2.5, 2.5, n), rng.uniform(-1.8, 1.8, n), rng.uniform(2.5, 7.0, n)]
    T_wc2 = np.eye(4)
    T_wc2[:3, :3] = Rotation.from_rotvec([0.02, -0.06, 0.01]).as_matrix()
    T_wc2[:3, 3] = [0.35, 0.05, 0.05]

    def proj(T_wc):
        T_cw = invert_pose(T_wc)
        Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
        return Xc[:, :2] / Xc[:, 2:3] @ K[:2, :2].T + K[:2, 2]

    return proj(np.eye(4)) + rng.normal(0, noise, (n, 2)), proj(T_wc2) + rng.normal(0, noise, (n, 2))


def _with_false_tracks(seed=0):
    p1, p2 = _views(seed=seed)
    rng = np.random.default_rng(seed + 1)
    bad = rng.choice(len(p1), 20, replace=False)
    p2 = p2.copy()
    p2[bad] += rng.normal(0, 1.5, (20, 2))  # tracks a little off: still within the 2 px triangulation gate
    return p1, p2, bad


def test_off_by_default():
    assert InitializationConfig().points_essential_inliers is False


def test_on_every_map_point_is_an_essential_inlier_and_fewer_false_tracks_remain():
    p1, p2, bad = _with_false_tracks()
    off = initialize_two_view(K, p1, p2, InitializationConfig())
    on = initialize_two_view(K, p1, p2, InitializationConfig(points_essential_inliers=True))
    assert off.ok and on.ok, (off.reason, on.reason)
    cv2.setRNGSeed(0)
    _, mask = cv2.findEssentialMat(p1, p2, K, cv2.RANSAC, 0.999, InitializationConfig().ransac_threshold_px)
    inl = mask.ravel().astype(bool)
    assert not np.any(on.good & ~inl)
    assert np.all(on.good <= off.good) and on.good.sum() < off.good.sum()
    assert on.good[bad].sum() < off.good[bad].sum()
