import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import Keyframe
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.motion_prior import add_rotation_rate_factors, add_velocity_factors, rotation_rate_residual, velocity_residual

from tests.slam.test_bundle_adjustment import K, _map


def _pose(rotvec, t):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    T[:3, 3] = t
    return T


def _graph(kfs, sigma_ratio=0.1, add=add_velocity_factors):
    """The keyframes' poses as values and ``add``'s motion factors over them, the newest keyframe free."""
    import gtsam
    from gtsam.symbol_shorthand import X

    graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    for kf in kfs:
        values.insert(X(kf.id), gtsam.Pose3(kf.T_wc))
    n = add(graph, kfs, {kf.id for kf in kfs}, {kfs[-1].id}, sigma_ratio)
    return graph, values, n


def _check_jacobians(graph, values, kfs, atol):
    """The linearised graph's single factor's columns against finite differences of its unwhitened error, with
    ``atol(num)`` the tolerance for a numeric column ``num``."""
    import gtsam
    from gtsam.symbol_shorthand import X

    f = graph.at(0)
    e0 = f.unwhitenedError(values)
    A, b = graph.linearize(values).jacobian()
    # Whitened: rows = residual / sigma; columns = the three poses' tangent spaces in key order. The linearisation
    # scales rows and right-hand side alike (sigma and Huber weight): undo it with |e| / |b|.
    scale = np.linalg.norm(e0) / max(np.linalg.norm(b), 1e-12)
    eps = 1e-6
    for i, kf in enumerate(kfs):
        for d in range(6):
            delta = np.zeros(6)
            delta[d] = eps
            v2 = gtsam.Values(values)
            v2.update(X(kf.id), values.atPose3(X(kf.id)).retract(delta))
            num = (f.unwhitenedError(v2) - e0) / eps
            np.testing.assert_allclose(A[:, 6 * i + d] * scale, num, atol=atol(num))


def test_velocity_factor_jacobians_match_finite_differences():
    kfs = [Keyframe(0, 0, _pose([0.1, -0.2, 0.3], [0, 0, 0])), Keyframe(1, 40_000, _pose([0.2, 0.1, -0.1], [0.1, 0.02, 0.0])),
           Keyframe(2, 100_000, _pose([-0.3, 0.2, 0.1], [0.3, 0.01, -0.05]))]
    graph, values, n = _graph(kfs)
    assert n == 1
    _check_jacobians(graph, values, kfs, lambda num: 1e-4)


def test_velocity_factor_pulls_a_speed_jump_back_to_constant_velocity():
    import gtsam
    from gtsam.symbol_shorthand import X

    # Two fixed keyframes moving 0.1 per 50 ms; the third sits 60 % too far (a scale jump) under a loose prior.
    kfs = [Keyframe(k, 50_000 * k, _pose([0, 0, 0], [0.1 * k, 0, 0])) for k in range(3)]
    kfs[2].T_wc[0, 3] = 0.1 + 0.16
    graph, values, _ = _graph(kfs)
    tight, loose = gtsam.noiseModel.Isotropic.Sigma(6, 1e-6), gtsam.noiseModel.Isotropic.Sigma(6, 1.0)
    for kf in kfs:
        graph.add(gtsam.PriorFactorPose3(X(kf.id), gtsam.Pose3(kf.T_wc), tight if kf.id < 2 else loose))
    out = gtsam.LevenbergMarquardtOptimizer(graph, values, gtsam.LevenbergMarquardtParams()).optimize()
    assert abs(out.atPose3(X(2)).translation()[0] - 0.2) < 0.01
    assert np.linalg.norm(velocity_residual(np.zeros(3), np.r_[0.1, 0, 0], np.r_[0.2, 0, 0], 0.05, 0.05)) == 0.0


def test_velocity_factors_skip_long_gaps_and_all_fixed_triples():
    kfs = [Keyframe(k, 50_000 * k, _pose([0, 0, 0], [0.1 * k, 0, 0])) for k in range(4)]
    kfs[3].t_us = kfs[2].t_us + 2_000_000
    import gtsam

    graph = gtsam.NonlinearFactorGraph()
    assert add_velocity_factors(graph, kfs, {0, 1, 2, 3}, {2, 3}, 0.1) == 1  # (0, 1, 2); (1, 2, 3) spans a 2 s gap
    assert add_velocity_factors(graph, kfs, {0, 1, 2, 3}, set(), 0.1) == 0


def test_local_ba_with_velocity_prior_still_fits_a_constant_velocity_map():
    # _map's keyframes move at one velocity: the prior agrees with the images and the BA still converges.
    m, X, true_T = _map(n_kf=5)
    before = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    rep = local_bundle_adjustment(m, K, window=5, iterations=20, huber_px=2.0, n_fixed=2, velocity_sigma_ratio=0.1)
    after = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    assert rep.final_error < 0.1 * rep.initial_error
    assert after < 0.5 * before


def _rate_graph(kfs, sigma=0.5):
    return _graph(kfs, sigma, add_rotation_rate_factors)


def test_rotation_rate_factor_jacobians_match_finite_differences():
    kfs = [Keyframe(0, 0, _pose([0.1, -0.2, 0.3], [0, 0, 0])), Keyframe(1, 40_000, _pose([0.13, -0.18, 0.31], [0.1, 0.02, 0.0])),
           Keyframe(2, 100_000, _pose([0.15, -0.17, 0.35], [0.3, 0.01, -0.05]))]
    graph, values, n = _rate_graph(kfs)
    assert n == 1
    # First-order inverse right Jacobians: exact enough for rotations a few degrees apart.
    _check_jacobians(graph, values, kfs, lambda num: 0.02 * np.abs(num).max() + 1e-6)


def test_rotation_rate_factor_pulls_a_rate_jump_back_to_constant_rate():
    import gtsam
    from gtsam.symbol_shorthand import X

    # Two fixed keyframes turning 1 deg per 50 ms about x; the third turned 3 deg (a rotation collapse) under a loose prior.
    kfs = [Keyframe(k, 50_000 * k, _pose([np.radians(k), 0, 0], [0.1 * k, 0, 0])) for k in range(3)]
    kfs[2].T_wc[:3, :3] = Rotation.from_rotvec([np.radians(1 + 3), 0, 0]).as_matrix()
    graph, values, _ = _rate_graph(kfs, sigma=np.radians(5.0))
    tight, loose = gtsam.noiseModel.Isotropic.Sigma(6, 1e-6), gtsam.noiseModel.Isotropic.Sigma(6, 1.0)
    for kf in kfs:
        graph.add(gtsam.PriorFactorPose3(X(kf.id), gtsam.Pose3(kf.T_wc), tight if kf.id < 2 else loose))
    out = gtsam.LevenbergMarquardtOptimizer(graph, values, gtsam.LevenbergMarquardtParams()).optimize()
    angle = Rotation.from_matrix(out.atPose3(X(2)).rotation().matrix()).as_rotvec()
    np.testing.assert_allclose(angle, [np.radians(2), 0, 0], atol=np.radians(0.05))
    # The translation is left to the other factors.
    assert abs(out.atPose3(X(2)).translation()[0] - 0.2) < 1e-3
    R = [Rotation.from_rotvec([np.radians(k), 0, 0]).as_matrix() for k in range(3)]
    np.testing.assert_allclose(rotation_rate_residual(*R, 0.05, 0.05), 0.0, atol=1e-12)


def test_rotation_rate_factors_skip_long_gaps_and_all_fixed_triples():
    import gtsam

    kfs = [Keyframe(k, 50_000 * k, _pose([0.01 * k, 0, 0], [0.1 * k, 0, 0])) for k in range(4)]
    kfs[3].t_us = kfs[2].t_us + 2_000_000
    graph = gtsam.NonlinearFactorGraph()
    assert add_rotation_rate_factors(graph, kfs, {0, 1, 2, 3}, {2, 3}, 0.5) == 1
    assert add_rotation_rate_factors(graph, kfs, {0, 1, 2, 3}, set(), 0.5) == 0


def test_local_ba_with_rotation_rate_prior_still_fits_a_constant_motion_map():
    m, X, true_T = _map(n_kf=5)
    before = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    rep = local_bundle_adjustment(m, K, window=5, iterations=20, huber_px=2.0, n_fixed=2, rotation_rate_sigma_rad_s=np.radians(40))
    after = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    assert rep.final_error < 0.1 * rep.initial_error
    assert after < 0.5 * before
