import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import InitializationConfig, TrackingConfig
from evpose.slam.geometry import project
from evpose.slam.map_restructure import RestructureConfig, RestructureMethod, maybe_restructure, restructure_due, restructure_map

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _true_poses(n_kf):
    poses = []
    for k in range(n_kf):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec([0.01 * k, 0.03 * k, 0]).as_matrix()
        # The first step is short (a two-view map over a tiny baseline), the later ones ten times longer.
        T[:3, 3] = [0.02 + 0.2 * (k - 1), 0.02 * k, 0.01 * k] if k else np.zeros(3)
        poses.append(T)
    return poses


def _map(seed=0, n_kf=5, n_pts=120, depth_noise=0.0, pose_noise=0.0):
    """Keyframes seeing every point without noise; points pushed along their first ray, later keyframes moved."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2, 2, n_pts), rng.uniform(-1.5, 1.5, n_pts), rng.uniform(3, 6, n_pts)]
    true_T = _true_poses(n_kf)
    m = SlamMap(0)
    for k, T in enumerate(true_T):
        Tn = T.copy()
        if k >= 2:
            Tn[:3, 3] += rng.normal(0, pose_noise, 3)
        uv = project(K, invert_pose(T), X)[0]
        m.keyframes.append(Keyframe(k, 10_000 * k, Tn, {j: uv[j].copy() for j in range(n_pts)}))
    for j in range(n_pts):
        obs = {k: m.keyframes[k].obs[j] for k in range(n_kf)}
        m.points[j] = MapPoint(j, X[j] * (1.0 + rng.normal(0, depth_noise)), obs, j, 1)
    return m, X, true_T


def test_restructure_is_off_by_default():
    m, _, _ = _map()
    assert restructure_due(m, K, RestructureConfig()) is None
    assert maybe_restructure(m, K, RestructureConfig(), InitializationConfig(), TrackingConfig(), {}) is None


def test_restructure_is_due_once_the_baseline_has_grown_the_given_times():
    m, _, _ = _map(n_kf=5)
    cfg = RestructureConfig(baseline_ratio=5.0, method=RestructureMethod.RETRIANGULATE)
    # Keyframe 4 is ~21 times as far from keyframe 0 as keyframe 1 is, keyframe 2 ~7.5 times.
    assert restructure_due(m, K, cfg) == 4
    m.keyframes = m.keyframes[:3]
    assert restructure_due(m, K, RestructureConfig(baseline_ratio=20.0, method=RestructureMethod.RETRIANGULATE)) is None
    assert restructure_due(m, K, RestructureConfig(baseline_ratio=6.0, method=RestructureMethod.RETRIANGULATE, times=2)) == 2
    m.restructured = 1  # a second time needs twice the ratio
    assert restructure_due(m, K, RestructureConfig(baseline_ratio=6.0, method=RestructureMethod.RETRIANGULATE, times=2)) is None


def test_retriangulation_moves_points_to_their_widest_pair():
    m, X, _ = _map(depth_noise=0.3)
    before = np.median(np.linalg.norm(m.point_array() - X, axis=1))
    cfg = RestructureConfig(baseline_ratio=3.0, method=RestructureMethod.RETRIANGULATE, ba_iterations=0)
    rep = maybe_restructure(m, K, cfg, InitializationConfig(), TrackingConfig(), {})
    assert rep is not None and rep.ok and m.restructured == 1
    after = np.median(np.linalg.norm(m.point_array() - X, axis=1))
    assert before > 0.3 and after < 1e-6
    assert maybe_restructure(m, K, cfg, InitializationConfig(), TrackingConfig(), {}) is None  # once only


def test_two_view_restructure_recovers_poses_and_keeps_the_pair_distance():
    m, X, true_T = _map(pose_noise=0.05)
    j = 4
    d_before = np.linalg.norm(m.keyframes[j].T_wc[:3, 3])
    err_before = max(np.linalg.norm(m.keyframes[k].T_wc[:3, 3] - true_T[k][:3, 3]) for k in range(2, 5))
    t2p = {t: t for t in range(len(X))}
    cfg = RestructureConfig(baseline_ratio=3.0, method=RestructureMethod.TWO_VIEW)
    rep = restructure_map(m, K, j, cfg, InitializationConfig(), TrackingConfig(), t2p)
    assert rep.ok, rep.reason
    # The gauge: keyframe 0 stays, the pair's distance is the one before (the true one here up to the noise).
    np.testing.assert_allclose(m.keyframes[0].T_wc, np.eye(4))
    assert abs(np.linalg.norm(m.keyframes[j].T_wc[:3, 3]) - d_before) < 1e-9
    s = np.linalg.norm(true_T[j][:3, 3]) / d_before
    err_after = max(np.linalg.norm(s * m.keyframes[k].T_wc[:3, 3] - true_T[k][:3, 3]) for k in range(1, 5))
    assert err_before > 0.03 and err_after < 1e-3
    for k in range(5):
        assert np.degrees(Rotation.from_matrix(m.keyframes[k].T_wc[:3, :3].T @ true_T[k][:3, :3]).magnitude()) < 0.05
    assert len(t2p) == len(m.points)


def test_slam_retriangulates_a_young_map_once_and_keeps_tracking_it():
    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.slam import SlamConfig, run_slam
    from slam_synthetic import make_recording

    rec = make_recording(duration_s=1.0, speed=1.5, seed=5)
    cfg = SlamConfig()
    cfg.restructure.baseline_ratio = 3.0
    run = run_slam(rec, cfg)
    m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s)
    assert [mp.restructured for mp in run.atlas.maps] == [1]
    assert m.tracked_fraction >= 0.8 and m.ate_percent <= 3.0  # 2.41 % without it
