import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.bundle_adjustment import local_bundle_adjustment
from slam_synthetic import sideways_map

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _map(seed=0, n_kf=4, n_pts=80, point_noise=0.2, pose_noise=0.03):
    rng = np.random.default_rng(seed)

    def perturb(k, T):
        if k >= 1:  # keyframe 0 (and 1 for scale) keep their true pose
            T[:3, 3] += rng.normal(0, pose_noise, 3) * (k >= 2)

    return sideways_map(rng, K, n_kf, n_pts, [0.15, 0.01, 0], point_noise, perturb)


def test_local_bundle_adjustment_reduces_point_and_pose_error():
    m, X, true_T = _map()
    before_pts = np.median(np.linalg.norm(m.point_array() - X, axis=1))
    before_pose = np.linalg.norm(m.keyframes[3].T_wc[:3, 3] - true_T[3][:3, 3])
    rep = local_bundle_adjustment(m, K, window=4, iterations=20, huber_px=2.0, n_fixed=2)
    assert rep.final_error < 0.1 * rep.initial_error
    after_pts = np.median(np.linalg.norm(m.point_array() - X, axis=1))
    after_pose = np.linalg.norm(m.keyframes[3].T_wc[:3, 3] - true_T[3][:3, 3])
    assert after_pts < 0.5 * before_pts
    assert after_pose < 0.5 * before_pose
    # Fixed keyframes do not move.
    assert np.array_equal(m.keyframes[0].T_wc, true_T[0])


def test_local_bundle_adjustment_with_zero_iterations_leaves_the_map_alone():
    m, _, _ = _map()
    pts = m.point_array().copy()
    local_bundle_adjustment(m, K, window=4, iterations=0, huber_px=2.0)
    assert np.array_equal(pts, m.point_array())


def test_scale_anchor_holds_the_baseline_of_the_two_oldest_keyframes():
    # One fixed keyframe leaves the monocular scale free; the anchor keeps the window's first baseline where it was.
    m, _, _ = _map(seed=1, n_kf=5, pose_noise=0.02)
    for p in m.points.values():
        p.xyz = 0.7 * p.xyz  # points at the wrong scale pull the free keyframes towards a shrunk map
    d0 = np.linalg.norm(m.keyframes[1].T_wc[:3, 3] - m.keyframes[0].T_wc[:3, 3])
    rep = local_bundle_adjustment(m, K, window=5, iterations=20, huber_px=2.0, n_fixed=1, scale_anchor=0.01)
    d1 = np.linalg.norm(m.keyframes[1].T_wc[:3, 3] - m.keyframes[0].T_wc[:3, 3])
    assert abs(d1 / d0 - 1.0) < 0.03
    assert rep.final_error < 0.1 * rep.initial_error


def test_scale_anchor_is_deterministic():
    a, _, _ = _map(seed=2, n_kf=5)
    b, _, _ = _map(seed=2, n_kf=5)
    for m in (a, b):
        local_bundle_adjustment(m, K, window=5, iterations=10, huber_px=2.0, n_fixed=1, scale_anchor=0.02)
    assert np.array_equal(a.point_array(), b.point_array())
    assert all(np.array_equal(x.T_wc, y.T_wc) for x, y in zip(a.keyframes, b.keyframes))


def test_a_pair_sigma_overrides_the_rotation_prior_sigma_of_that_pair_only():
    # A wrong rotation prior (1 deg off the truth) between keyframes 2 and 3: the tight sigma pulls keyframe 3 towards
    # it; the same prior with a loose sigma of its own for that pair leaves keyframe 3 where the images alone put it.
    def adjusted_rotation_error(priors, sigmas):
        m, _, true_T = _map(seed=3, n_kf=4, n_pts=80)
        R23 = true_T[2][:3, :3].T @ true_T[3][:3, :3] @ Rotation.from_rotvec([0, 0, np.radians(1.0)]).as_matrix()
        local_bundle_adjustment(m, K, window=4, iterations=20, huber_px=2.0, n_fixed=2, rotation_priors={(2, 3): R23} if priors else None,
                                rotation_sigma_rad=np.radians(0.01), rotation_sigmas_rad=sigmas)
        R = m.keyframes[3].T_wc[:3, :3].T @ true_T[3][:3, :3]
        return np.degrees(np.linalg.norm(Rotation.from_matrix(R).as_rotvec()))

    images_only = adjusted_rotation_error(False, None)
    assert adjusted_rotation_error(True, None) > images_only + 0.3
    assert abs(adjusted_rotation_error(True, {(2, 3): np.radians(10.0)}) - images_only) < 0.01


def test_an_observation_on_a_straight_edge_gets_the_along_edge_sigma_and_a_corner_stays_isotropic():
    from types import SimpleNamespace

    import cv2
    import gtsam

    from evpose.slam.bundle_adjustment import _edge_noise

    img = np.zeros((60, 80), np.uint8)
    img[:, 30] = 255  # a vertical edge
    img[45, 30:] = 255  # meeting a horizontal one: a corner at (30, 45)
    kf = SimpleNamespace(id=0, image8=cv2.GaussianBlur(img, (0, 0), 1.0))
    tensors: dict = {}
    nm = _edge_noise(gtsam, kf, (30.0, 15.0), tensors, 5.0, 0.1, 2.0)
    # Five pixels along the edge weigh as one across it.
    assert abs(np.linalg.norm(nm.unweightedWhiten(np.array([0.0, 5.0]))) - 1.0) < 0.01
    assert abs(np.linalg.norm(nm.unweightedWhiten(np.array([5.0, 0.0]))) - 5.0) < 0.05
    assert _edge_noise(gtsam, kf, (30.0, 45.0), tensors, 5.0, 0.1, 2.0) is None  # corner
    assert _edge_noise(gtsam, kf, (70.0, 10.0), tensors, 5.0, 0.1, 2.0) is None  # blank: no gradient
    assert _edge_noise(gtsam, SimpleNamespace(id=1, image8=None), (30.0, 15.0), {}, 5.0, 0.1, 2.0) is None
