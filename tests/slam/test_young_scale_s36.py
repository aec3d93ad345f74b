import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.config import SlamConfig
from evpose.slam.young_scale import (YoungScaleConfig, add_speed_factors, reference_speed, speed_factor_hook,
                                     speed_pairs)

from tests.slam.test_bundle_adjustment import K, _map


def _kf(k, t_us, x):
    T = np.eye(4)
    T[0, 3] = x
    return Keyframe(k, t_us, T, {})


def _line(n, dt_us=40_000, speed=2.0):
    """``n`` keyframes along x at ``speed`` map units per second, ``dt_us`` apart."""
    return [_kf(k, k * dt_us, speed * k * dt_us / 1e6) for k in range(n)]


def test_reference_speed_is_the_path_speed_before_the_newest_step():
    kfs = _line(6)
    kfs[-1].T_wc[0, 3] += 1.0  # the newest step (PnP just placed it) is left out of the reference
    assert abs(reference_speed(kfs, span_s=1.0, max_gap_s=0.15) - 2.0) < 1e-12
    # Only the steps within span_s before the newest keyframe's predecessor: here the last two of them.
    kfs[0].T_wc[0, 3] -= 5.0
    assert abs(reference_speed(kfs, span_s=0.08, max_gap_s=0.15) - 2.0) < 1e-12
    assert reference_speed(kfs, span_s=1.0, max_gap_s=0.15) > 2.0
    # Fewer than two steps: no reference.
    assert reference_speed(kfs, span_s=0.04, max_gap_s=0.15) is None
    assert reference_speed(kfs[:2], span_s=1.0, max_gap_s=0.15) is None


def test_reference_speed_skips_steps_over_a_gap():
    kfs = _line(5)
    for kf in kfs[2:]:
        kf.t_us += 500_000  # a coast or blank between keyframes 1 and 2: that step is no speed measurement
    assert reference_speed(kfs, span_s=10.0, max_gap_s=0.15) is not None
    assert abs(reference_speed(kfs, span_s=10.0, max_gap_s=0.15) - 2.0) < 1e-12
    kfs2 = _line(4)
    kfs2[2].t_us += 500_000
    kfs2[3].t_us += 500_000
    assert reference_speed(kfs2, span_s=10.0, max_gap_s=0.15) is None  # one step left


def test_speed_pairs_need_one_free_keyframe_and_a_short_gap():
    kfs = _line(4)
    kfs[3].t_us += 1_000_000
    pairs = [(a.id, b.id) for a, b, _ in speed_pairs(kfs, {0, 1, 2, 3}, {2, 3}, 0.15)]
    assert pairs == [(1, 2)]
    assert list(speed_pairs(kfs, {0, 1, 2, 3}, set(), 0.15)) == []
    assert [(a.id, b.id) for a, b, _ in speed_pairs(kfs, {1, 2}, {1}, 0.15)] == [(1, 2)]


def test_speed_factor_pulls_a_too_long_step_back_to_the_reference_speed():
    import gtsam
    from gtsam.symbol_shorthand import X

    kfs = _line(3)  # 0.08 apart
    kfs[2].T_wc[0, 3] = 0.08 + 0.2  # the newest step 2.5 times too long
    kfs[2].T_wc[1, 3] = 0.05
    graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    tight, loose = gtsam.noiseModel.Isotropic.Sigma(6, 1e-6), gtsam.noiseModel.Isotropic.Sigma(6, 10.0)
    for kf in kfs:
        values.insert(X(kf.id), gtsam.Pose3(kf.T_wc))
        graph.add(gtsam.PriorFactorPose3(X(kf.id), gtsam.Pose3(kf.T_wc), tight if kf.id < 2 else loose))
    n = add_speed_factors(graph, kfs, {0, 1, 2}, {2}, v_ref=2.0, sigma_ratio=0.05, huber=100.0, max_gap_s=0.15)
    assert n == 1
    out = gtsam.LevenbergMarquardtOptimizer(graph, values, gtsam.LevenbergMarquardtParams()).optimize()
    p1, p2 = out.atPose3(X(1)).translation(), out.atPose3(X(2)).translation()
    assert abs(np.linalg.norm(p2 - p1) - 0.08) < 0.005
    # Only the length is held: the step keeps its direction (sideways share of the original step).
    d = (p2 - p1) / np.linalg.norm(p2 - p1)
    d0 = np.array([0.2, 0.05, 0.0]) / np.linalg.norm([0.2, 0.05, 0.0])
    assert d @ d0 > 0.99


def test_hook_is_none_when_off_too_old_or_without_reference():
    m = SlamMap(0)
    m.keyframes = _line(6)
    assert speed_factor_hook(m, YoungScaleConfig(), m.keyframes[-1].t_us) is None  # off by default
    on = YoungScaleConfig(speed_prior=0.3, span_s=1.0)
    assert speed_factor_hook(m, on, m.keyframes[-1].t_us) is not None
    young = YoungScaleConfig(speed_prior=0.3, span_s=1.0, max_age_s=0.1)
    assert speed_factor_hook(m, young, m.keyframes[-1].t_us) is None  # 0.2 s old
    m2 = SlamMap(1)
    m2.keyframes = _line(2)
    assert speed_factor_hook(m2, on, m2.keyframes[-1].t_us) is None
    assert SlamConfig().young_scale.speed_prior == 0.0


def test_local_ba_calls_the_extra_factors_on_the_free_keyframes_and_the_prior_fits_a_constant_speed_map():
    m, _, true_T = _map(n_kf=5)
    for k, kf in enumerate(m.keyframes):
        kf.t_us = 40_000 * k  # _map's keyframes move 0.15 per step at one speed
    seen = []

    def spy(graph, present, free):
        seen.append((set(present), set(free)))
        return 0

    local_bundle_adjustment(m, K, window=5, iterations=5, huber_px=2.0, n_fixed=2, extra_factors=spy)
    assert seen == [({0, 1, 2, 3, 4}, {2, 3, 4})]
    m, _, true_T = _map(n_kf=5)
    for k, kf in enumerate(m.keyframes):
        kf.t_us = 40_000 * k
    before = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    hook = speed_factor_hook(m, YoungScaleConfig(speed_prior=0.2, span_s=1.0), m.keyframes[-1].t_us)
    rep = local_bundle_adjustment(m, K, window=5, iterations=20, huber_px=2.0, n_fixed=2, extra_factors=hook)
    after = np.mean([np.linalg.norm(kf.T_wc[:3, 3] - T[:3, 3]) for kf, T in zip(m.keyframes, true_T)])
    assert rep.final_error < 0.1 * rep.initial_error
    assert after < 0.5 * before

