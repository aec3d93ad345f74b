"""The scale anchors of the inertial local BA (:class:`evpose.slam.inertial_window_config.InertialWindowConfig`)."""

import numpy as np
import pytest

from evpose.slam.atlas import Keyframe
from evpose.slam.config import SlamConfig
from evpose.slam.inertial_ba import InertialState, fixed_keyframes, inertial_local_bundle_adjustment, spread_ratio
from evpose.slam.inertial_window_config import InertialWindowConfig
from slam_synthetic import inertial_truth_map, make_recording

K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=1.2, speed=1.0, seed=5, shake=0.08, n_points=10)


def _map(rec, idx, stretch):
    """Keyframes at samples ``idx`` of the truth (gravity rotated to -z), their positions and the points stretched by
    ``stretch`` about the first keyframe (a map whose scale is off), with metric velocities from the truth."""
    m, vel = inertial_truth_map(rec, K, idx, stretch)
    return m, InertialState(vel, np.zeros(3), np.zeros(3))


def _positions(m):
    return np.array([kf.T_wc[:3, 3] for kf in m.keyframes])


def test_a_result_rescaling_the_window_is_refused_and_leaves_it_as_it_was(shaken):
    idx = list(range(50, 1150, 150))  # keyframes 0.15 s apart: the IMU factors pull a 3x stretched map back
    m, state = _map(shaken, idx, 3.0)
    before = _positions(m)
    err = inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=30, huber_px=2.0)
    assert np.isfinite(err)
    assert spread_ratio(before, _positions(m)) < 1 / 1.5  # the BA shrinks the window towards metric

    m, state = _map(shaken, idx, 3.0)
    pts = {k: p.xyz.copy() for k, p in m.points.items()}
    vel = {k: v.copy() for k, v in state.velocities.items()}
    err = inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=30, huber_px=2.0,
                                           anchors=InertialWindowConfig(max_scale_change=1.5))
    assert np.isnan(err)
    assert np.array_equal(_positions(m), before)
    assert all(np.array_equal(m.points[k].xyz, v) for k, v in pts.items())
    assert all(np.array_equal(state.velocities[k], v) for k, v in vel.items())
    assert np.array_equal(state.bias_gyro, np.zeros(3))


def test_a_clamped_result_changes_the_window_scale_by_exactly_the_bound(shaken):
    idx = list(range(50, 1150, 150))
    m, state = _map(shaken, idx, 3.0)
    before = _positions(m)
    err = inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=30, huber_px=2.0,
                                           anchors=InertialWindowConfig(max_scale_change=1.5, clamp_scale=True))
    assert np.isfinite(err)
    assert spread_ratio(before, _positions(m)) == pytest.approx(1 / 1.5, rel=1e-9)
    assert np.abs(_positions(m)[0] - before[0]).max() < 1e-5  # rescaled about the fixed first camera


def test_a_window_result_within_the_bound_is_kept(shaken):
    idx = list(range(50, 1150, 150))
    m, state = _map(shaken, idx, 1.0)
    before = _positions(m)
    err = inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=30, huber_px=2.0,
                                           anchors=InertialWindowConfig(max_scale_change=1.5))
    assert np.isfinite(err)
    assert 1 / 1.5 < spread_ratio(before, _positions(m)) < 1.5


def test_fixed_keyframes_are_thinned_older_keyframes_oldest_first():
    kfs = [Keyframe(k, 5000 * k, np.eye(4), {}) for k in range(100)]  # a keyframe every 5 ms, as indoors
    out = fixed_keyframes(kfs, kfs[94], 4, 0.2)
    t = [k.t_us for k in out]
    assert len(out) == 4 and t == sorted(t)
    assert all(k.t_us < kfs[94].t_us for k in out)
    assert all(b - a >= 50_000 for a, b in zip(t, t[1:] + [kfs[94].t_us]))
    assert [k.id for k in fixed_keyframes(kfs, kfs[94], 3, 0.0)] == [91, 92, 93]


def test_the_anchors_are_one_nested_field_of_the_inertial_config():
    ic = SlamConfig().inertial
    assert isinstance(ic.ba_window, InertialWindowConfig)


def test_map_velocity_is_the_keyframe_path_over_the_span():
    from evpose.slam.inertial_ba import map_velocity

    kfs = []
    for k in range(100):
        T = np.eye(4)
        T[:3, 3] = [2.0 * 0.005 * k, 0.0, -0.5 * 0.005 * k]  # 2 and -0.5 map units per second, keyframes 5 ms apart
        kfs.append(Keyframe(k, 5000 * k, T, {}))
    assert np.allclose(map_velocity(kfs, kfs[90], 0.3), [2.0, 0.0, -0.5])
    assert map_velocity(kfs, kfs[10], 0.3) is None  # the map does not reach that far back
