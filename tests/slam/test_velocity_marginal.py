"""The inertial local BA's velocity prior carried from the previous BA's marginal
(:mod:`evpose.slam.velocity_marginal`, ``InertialWindowConfig.velocity_marginal``)."""

import numpy as np
import pytest

from evpose.slam.inertial_ba import InertialState, inertial_local_bundle_adjustment
from evpose.slam.inertial_window_config import InertialWindowConfig
from evpose.slam.velocity_marginal import carried_velocity_noise, velocity_marginals
from slam_synthetic import inertial_truth_map, make_recording

K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=1.2, speed=1.0, seed=5, shake=0.08, n_points=10)


def test_the_marginal_of_a_velocity_chained_to_a_prior_adds_the_variances():
    import gtsam
    from gtsam.symbol_shorthand import V

    g = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    v.insert(V(1), np.zeros(3))
    v.insert(V(2), np.ones(3))
    g.add(gtsam.PriorFactorVector(V(1), np.zeros(3), gtsam.noiseModel.Isotropic.Sigma(3, 0.3)))
    g.add(gtsam.BetweenFactorVector(V(1), V(2), np.ones(3), gtsam.noiseModel.Isotropic.Sigma(3, 0.4)))
    cov = velocity_marginals(g, v, [1, 2])
    assert np.allclose(cov[1], 0.09 * np.eye(3), rtol=1e-6)
    assert np.allclose(cov[2], 0.25 * np.eye(3), rtol=1e-6)


def test_the_marginal_survives_a_point_whose_depth_two_views_leave_undetermined():
    import gtsam
    from gtsam.symbol_shorthand import L, V, X

    cal = gtsam.Cal3_S2(200.0, 200.0, 0.0, 119.5, 89.5)
    g = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    for k in (0, 1):
        v.insert(X(k), gtsam.Pose3())  # two views from the same place: no baseline
        g.add(gtsam.PriorFactorPose3(X(k), gtsam.Pose3(), gtsam.noiseModel.Isotropic.Sigma(6, 1e-3)))
        g.add(gtsam.GenericProjectionFactorCal3_S2(np.array([119.5, 89.5]), gtsam.noiseModel.Isotropic.Sigma(2, 1.0), X(k), L(0), cal))
    v.insert(L(0), gtsam.Point3(0.0, 0.0, 2.0))
    v.insert(V(0), np.zeros(3))
    g.add(gtsam.PriorFactorVector(V(0), np.zeros(3), gtsam.noiseModel.Isotropic.Sigma(3, 0.2)))
    with pytest.raises(RuntimeError):
        gtsam.Marginals(g, v)  # what the full BA after an indoor initialisation meets
    cov = velocity_marginals(g, v, [0])
    assert np.allclose(cov[0], 0.04 * np.eye(3), rtol=1e-6)


def test_the_carried_prior_is_never_looser_than_the_fixed_one_and_keeps_its_floor():
    import gtsam

    cov = np.diag([1e-8, 0.01, 4.0])
    nm = carried_velocity_noise(cov, InertialWindowConfig(velocity_marginal=True, velocity_marginal_min_sigma=0.01), 0.5)
    R = nm.R()  # square-root information: covariance = inv(R' R)
    c = np.linalg.inv(R.T @ R)
    assert np.allclose(np.diag(c), [1e-8 + 1e-4, 0.01 + 1e-4, 0.25], rtol=1e-6)
    assert isinstance(nm, gtsam.noiseModel.Gaussian)
    c2 = np.linalg.inv(carried_velocity_noise(cov, InertialWindowConfig(velocity_marginal_inflation=4.0), 0.5).R() ** 2)
    assert c2[1, 1] == pytest.approx(0.04, rel=1e-6)


def _map(rec, idx):
    m, vel = inertial_truth_map(rec, K, idx, 1.0)
    return m, InertialState(vel, np.zeros(3), np.zeros(3))


def test_the_bundle_adjustment_keeps_the_window_velocity_covariances_only_when_asked(shaken):
    idx = list(range(50, 1150, 150))
    m, state = _map(shaken, idx)
    inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=10, huber_px=2.0)
    assert state.velocity_cov == {}
    m, state = _map(shaken, idx)
    inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=10, huber_px=2.0, marginals=True)
    assert set(state.velocity_cov) == {kf.id for kf in m.keyframes}
    first = state.velocity_cov[m.keyframes[0].id]
    assert np.all(np.linalg.eigvalsh(first) > 0)
    assert np.all(np.diag(first) < 0.25)  # tighter than the 0.5 m/s prior it started from


def test_a_carried_prior_holds_the_oldest_velocity_tighter_than_the_fixed_one(shaken):
    idx = list(range(50, 1150, 150))
    m, state = _map(shaken, idx)
    wrong = state.velocities[m.keyframes[-3].id] + np.array([0.3, -0.2, 0.1])
    outs = []
    for carried in (False, True):
        m, state = _map(shaken, idx)
        kf0 = m.keyframes[-3]
        state.velocities[kf0.id] = wrong.copy()  # the window's oldest starts 0.37 m/s off
        state.velocity_cov[kf0.id] = 1e-4 * np.eye(3)  # what an earlier BA claimed to know about it
        inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=3, iterations=20, huber_px=2.0,
                                         anchors=InertialWindowConfig(velocity_marginal=carried))
        outs.append(np.linalg.norm(state.velocities[kf0.id] - wrong))
    assert outs[1] < 0.1 * outs[0]


def test_a_scale_refinement_rescales_the_carried_covariances_with_the_map():
    from evpose.slam import SlamConfig, SlamMode
    from evpose.slam.atlas import Keyframe, SlamMap
    from evpose.slam.scale_refinement import refine_map_scale

    rec = make_recording(duration_s=2.0, speed=1.0, seed=5, shake=0.08)
    T = rec.ground_truth.matrices()
    m = SlamMap(0)
    for i, k in enumerate(range(0, 1900, 100)):
        P = T[k].copy()
        P[:3, 3] *= 5.0  # the first initialisation left the map 5 times too large
        m.keyframes.append(Keyframe(i, int(rec.ground_truth.t[k]), P))
    m.imu_initialised = True
    m.inertial = InertialState({}, np.zeros(3), np.zeros(3), {0: np.eye(3), 18: 4.0 * np.eye(3)})
    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    cfg.inertial.refine_min_scale = 0.0
    cfg.inertial.inertial_ba = False  # the covariances as the similarity leaves them (the BA would renew them)
    res = refine_map_scale(m, K, rec.imu, rec.calibration.T_cam_imu, rec.calibration.time_offset_us, cfg.inertial, 5, 2.0)
    assert res.ok and res.scale == pytest.approx(0.2, rel=0.02)
    assert np.allclose(m.inertial.velocity_cov[0], res.scale**2 * np.eye(3))
    assert np.allclose(m.inertial.velocity_cov[18], 4.0 * res.scale**2 * np.eye(3))
