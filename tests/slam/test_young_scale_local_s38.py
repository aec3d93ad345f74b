"""Each keyframe pair held to its own neighbours' speed (``YoungScaleConfig.local_reference``)."""

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.young_scale import (YoungScaleConfig, add_speed_factors, local_reference_speeds, reference_speed,
                                     speed_factor_hook)


def _kf(k, t_us, x):
    T = np.eye(4)
    T[0, 3] = x
    return Keyframe(k, t_us, T, {})


def _accelerating(n=13, dt_us=40_000, v0=1.0, acc=10.0):
    """``n`` keyframes along x at speed ``v0 + acc t`` (map units per second), ``dt_us`` apart."""
    return [_kf(k, k * dt_us, v0 * k * dt_us / 1e6 + 0.5 * acc * (k * dt_us / 1e6) ** 2) for k in range(n)]


def test_local_reference_follows_a_speed_change_where_one_reference_cannot():
    kfs = _accelerating()
    ref = local_reference_speeds(kfs, span_s=0.3, max_gap_s=0.15)
    # A middle pair (keyframes 5 -> 6, mid-time 0.22 s) with neighbours on both sides reads the speed there, 3.2.
    assert abs(ref[6] - 3.2) < 1e-9
    # Every pair it covers is nearer its own true speed than the speed the last 0.3 s give every pair (4.0 here).
    for kid, v in ref.items():
        true_v = 1.0 + 10.0 * (kid - 0.5) * 0.04
        assert abs(v - true_v) <= abs(4.0 - true_v) + 1e-9


def test_local_reference_leaves_out_the_pair_itself_the_newest_step_and_gaps():
    kfs = [_kf(k, k * 40_000, 0.08 * k + (0.1 if k >= 4 else 0.0)) for k in range(8)]  # 2 units/s, step 3 -> 4 too long
    kfs[-1].T_wc[0, 3] += 5.0  # the newest step (PnP just placed it) is no reference for anyone
    ref = local_reference_speeds(kfs, span_s=0.2, max_gap_s=0.15)
    assert abs(ref[4] - 2.0) < 1e-9  # the long pair itself is held to its neighbours
    assert abs(ref[7] - 2.0) < 1e-9  # the newest pair too, from its older neighbours
    assert abs(ref[5] - 0.34 / 0.12) < 1e-9  # a neighbour's error does reach it
    far = [_kf(k, k * 40_000 + (600_000 if k >= 4 else 0), 0.08 * k) for k in range(8)]
    ref2 = local_reference_speeds(far, span_s=0.2, max_gap_s=0.15)
    assert 4 not in ref2  # the pair over a 0.64 s gap: no measured step near it
    assert abs(ref2[2] - 2.0) < 1e-9  # and it is no reference for the others


def test_hook_uses_the_local_references_only_when_asked():
    import gtsam
    from gtsam.symbol_shorthand import X

    m = SlamMap(0)
    m.keyframes = _accelerating()
    window = reference_speed(m.keyframes, 0.3, 0.15)
    local = local_reference_speeds(m.keyframes, 0.3, 0.15)[1]
    assert abs(window - local) > 1.0
    for on, v in ((False, window), (True, local)):
        hook = speed_factor_hook(m, YoungScaleConfig(speed_prior=0.1, local_reference=on), t_us=500_000)
        graph = gtsam.NonlinearFactorGraph()
        assert hook(graph, {0, 1}, {1}) == 1  # one pair, 0 -> 1, in the window
        for d, zero in ((v * 0.04, True), ((window if on else local) * 0.04, False)):
            values = gtsam.Values()
            for kf in m.keyframes:
                T = kf.T_wc.copy()
                if kf.id == 1:
                    T[0, 3] = m.keyframes[0].T_wc[0, 3] + d
                values.insert(X(kf.id), gtsam.Pose3(T))
            assert (graph.error(values) < 1e-12) == zero  # the factor holds the pair at its reference's distance


def test_add_speed_factors_falls_back_to_the_window_reference():
    import gtsam

    kfs = _accelerating(5)
    graph = gtsam.NonlinearFactorGraph()
    n = add_speed_factors(graph, kfs, {0, 1, 2, 3, 4}, {1, 2, 3, 4}, v_ref=2.0, sigma_ratio=0.1, huber=2.0,
                          max_gap_s=0.15, local={2: 1.5})
    assert n == 4
