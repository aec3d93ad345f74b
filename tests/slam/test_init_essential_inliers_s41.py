"""``InitializationConfig.points_essential_inliers``: only the essential matrix's RANSAC inliers become map points."""

import cv2
import numpy as np

from evpose.slam.config import InitializationConfig
from evpose.slam.initialization import initialize_two_view
from tests.slam.test_initialization import K, _views


def _with_false_tracks(seed=0):
    p1, p2, _, _ = _views(planar=False, seed=seed)  # 150 points 2.5-7 m away, two poses 0.35 m apart, 0.3 px noise
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
