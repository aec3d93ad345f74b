"""``InitializationConfig.drop_static_matches``: a two-view attempt refused because its median match stood still is
tried on the matches that moved, when enough did (:func:`evpose.slam.initialization.moved_matches`)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam import SlamConfig
from evpose.slam.config import InitializationConfig
from evpose.slam.initialization import initialize_two_view, moved_matches

K = np.array([[200.0, 0, 120.0], [0, 200.0, 90.0], [0, 0, 1]])


def _pair(n_scene: int, n_still: int, seed: int = 0):
    """Scene points seen from two poses 15 cm and 2 deg apart, plus event-noise features that stay put."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2.0, 2.0, n_scene), rng.uniform(-1.5, 1.5, n_scene), rng.uniform(2.0, 5.0, n_scene)]
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.0, np.radians(2.0), 0.0]).as_matrix()
    T[:3, 3] = [0.15, 0.0, 0.02]

    def proj(T_wc):
        T_cw = invert_pose(T_wc)
        Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
        return Xc[:, :2] / Xc[:, 2:3] @ K[:2, :2].T + K[:2, 2]

    still = np.c_[rng.uniform(5, 235, n_still), rng.uniform(5, 175, n_still)]
    jitter = rng.normal(0, 0.1, (n_still, 2))
    p1 = np.r_[proj(np.eye(4)) + rng.normal(0, 0.2, (n_scene, 2)), still]
    p2 = np.r_[proj(T) + rng.normal(0, 0.2, (n_scene, 2)), still + jitter]
    return p1, p2


def test_on_by_default_behind_its_gate():
    # Session 39: on, gated by drop_static_after_s (tests/slam/test_drop_static_after_s39.py).
    assert SlamConfig().initialization.drop_static_matches is True
    assert SlamConfig().initialization.drop_static_after_s > 0


def test_a_moving_third_among_still_noise_is_kept_and_starts_where_the_whole_set_is_refused():
    p1, p2 = _pair(40, 80)
    cfg = InitializationConfig()
    refused = initialize_two_view(K, p1, p2, cfg)
    assert not refused.ok and "barely moved" in refused.reason
    moved = moved_matches(p1, p2, cfg)
    assert moved is not None
    assert moved[:40].all() and not moved[40:].any()
    assert initialize_two_view(K, p1[moved], p2[moved], cfg).ok


def test_no_mask_when_the_median_moved_or_too_few_moved():
    cfg = InitializationConfig()
    p1, p2 = _pair(80, 40)
    assert moved_matches(p1, p2, cfg) is None  # the median match moved: the start is tried on all as before
    p1, p2 = _pair(cfg.min_matches - 1, 80)
    assert moved_matches(p1, p2, cfg) is None  # too few moved: still refused as barely moved
    assert moved_matches(np.zeros((0, 2)), np.zeros((0, 2)), cfg) is None
