"""Event-only PnP poses refined with the map's predicted motion as a prior (TrackingConfig.pnp_motion_prior_ratio)."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import Atlas, Keyframe, MapPoint
from evpose.slam.geometry import project
from slam_pose_scene import K, scene
from slam_pose_scene import pose as _pose
from evpose.slam.pnp_motion_prior import refine_pose_with_pose_prior
from evpose.slam.pose_refit import refit_pose



def _scene(n=15, seed=0):
    return scene(n, seed)


def _centre_distance(T_cw_a, T_cw_b):
    return float(np.linalg.norm(invert_pose(T_cw_a)[:3, 3] - invert_pose(T_cw_b)[:3, 3]))


def test_free_prior_converges_to_the_reprojection_minimum():
    X = _scene()
    truth_wc = _pose([0.01, 0.03, 0.0], [0.1, 0.05, 0.0])
    uv, _ = project(K, invert_pose(truth_wc), X)
    start = invert_pose(_pose([0.0, 0.05, 0.0], [0.15, 0.0, 0.0]))
    out = refine_pose_with_pose_prior(K, X, uv, start, np.eye(4), 0.0, 0.0)
    assert np.allclose(out, invert_pose(truth_wc), atol=1e-6)


def test_prior_pulls_a_noisy_pose_towards_the_prediction_and_weakens_with_its_sigma():
    X = _scene(12, seed=2)
    truth_wc = _pose([0.0, 0.02, 0.0], [0.2, 0.0, 0.0])
    uv, _ = project(K, invert_pose(truth_wc), X)
    noisy = uv + np.random.default_rng(5).normal(0, 1.5, uv.shape)
    free = invert_pose(refit_pose(K, X, noisy, truth_wc))  # PnP's own minimum on the noisy pixels
    pred = invert_pose(truth_wc)  # a prediction at the truth
    d_free = _centre_distance(free, pred)
    tight = refine_pose_with_pose_prior(K, X, noisy, free, pred, np.radians(0.1), 0.1 * d_free)
    loose = refine_pose_with_pose_prior(K, X, noisy, free, pred, np.radians(0.1), 1e3)
    assert _centre_distance(tight, pred) < 0.3 * d_free
    assert _centre_distance(loose, pred) > 0.9 * d_free or np.isclose(d_free, 0.0)
    # Only the translation sigma given: the rotation stays the points' (the tight pose still moves its centre).
    t_only = refine_pose_with_pose_prior(K, X, noisy, free, pred, 0.0, 0.1 * d_free)
    assert _centre_distance(t_only, pred) < 0.5 * d_free


def test_read_time_re_solve_keeps_the_prior_of_a_pose_refined_online():
    X = _scene(12, seed=4)
    truth = _pose([0.0, 0.02, 0.0], [0.2, 0.0, 0.0])
    uv, _ = project(K, invert_pose(truth), X)
    online = _pose([0.0, 0.02, 0.0], [0.23, 0.0, 0.0])  # held 3 cm off by its prior
    out = {}
    for sigmas in (None, (np.radians(0.05), 1e-4)):
        m = Atlas(refit_K=K).new_map()
        m.keyframes.append(Keyframe(0, 0, np.eye(4)))
        for i, x in enumerate(X):
            m.points[i] = MapPoint(i, x.copy())
        m.add_pose(0, np.eye(4))
        m.add_pose(10, online)
        m.record_pose_observations(10, np.arange(len(X)), uv, np.zeros(0, np.int64), np.zeros((0, 2)), sigmas)
        out[sigmas is None] = m.trajectory().matrices()[1]
    assert np.allclose(out[True], truth, atol=1e-6)  # no prior: the points' pose
    assert np.allclose(out[False][:3, 3], online[:3, 3], atol=2e-3)  # a tight prior: stays near the online pose


def test_the_option_refines_event_only_pnp_poses_and_records_the_prior_for_the_re_solve():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from slam_synthetic import make_recording

    from evpose.core.camera import CameraCalibration
    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.slam import SlamConfig, run_slam

    rec = make_recording(duration_s=1.0, speed=1.5, calibration=CameraCalibration(240, 180, 200, 200, 119.5, 89.5), seed=5)
    runs = {}
    for ratio in (0.0, 1.0):
        cfg = SlamConfig()
        cfg.tracking.pnp_motion_prior_ratio = ratio
        runs[ratio] = run_slam(rec, cfg)
    sig = {r: [o.prior_sigmas for m in run.atlas.maps for o in m.traj_obs.values()] for r, run in runs.items()}
    assert sig[0.0] and all(s is None for s in sig[0.0])  # off: nothing refined, nothing recorded
    on = [s for s in sig[1.0] if s is not None]
    assert len(on) >= len(sig[1.0]) // 2 and all(s[0] == 0.0 and s[1] > 0 for s in on)  # rotation free, translation held
    m = atlas_metrics(runs[1.0].trajectories(), rec.ground_truth, correct_scale=True, duration_s=runs[1.0].duration_s)
    assert m.tracked_fraction > 0.8 and m.ate_percent < 5.0
