import numpy as np
import pytest

from evpose.slam.atlas import Keyframe
from evpose.slam.inertial_ba import InertialState, inertial_local_bundle_adjustment
from slam_synthetic import inertial_truth_map, make_recording

K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=1.2, speed=1.0, seed=5, shake=0.08, n_points=10)


def test_inertial_bundle_adjustment_pulls_a_perturbed_keyframe_back(shaken):
    idx = list(range(50, 1150, 150))
    m, vel = inertial_truth_map(shaken, K, idx, point_noise=0.02)  # gravity rotated into gtsam's -z
    truth = m.keyframes[-1].T_wc.copy()
    m.keyframes[-1].T_wc = truth.copy()
    m.keyframes[-1].T_wc[:3, 3] += [0.05, -0.03, 0.02]
    first = m.keyframes[0].T_wc.copy()
    state = InertialState(vel, np.zeros(3), np.array([0.004, -0.003, 0.002]))
    err = inertial_local_bundle_adjustment(m, state, K, shaken.imu, np.eye(4), 0, window=len(idx), iterations=30, huber_px=2.0)
    assert np.isfinite(err)
    before = np.linalg.norm([0.05, -0.03, 0.02])
    assert np.linalg.norm(m.keyframes[-1].T_wc[:3, 3] - truth[:3, 3]) < 0.25 * before
    assert np.abs(m.keyframes[0].T_wc - first).max() < 1e-6
    assert np.abs(state.bias_gyro - [0.004, -0.003, 0.002]).max() < 2e-3


def _kf(k, t_ms):
    return Keyframe(k, int(t_ms * 1000), np.eye(4), {})


def test_spanning_window_extends_a_short_window_back_with_thinned_keyframes():
    from evpose.slam.inertial_ba import spanning_window

    kfs = [_kf(k, 5.0 * k) for k in range(100)]  # a keyframe every 5 ms, as indoors
    out = spanning_window(kfs, 6, 0.3, 4)
    ids = [k.id for k in out]
    assert ids[-6:] == list(range(94, 100))
    older = out[:-6]
    assert len(older) == 4
    t = [k.t_us for k in out]
    assert all(b - a >= 60_000 for a, b in zip(t[:4], t[1:5]))  # 0.3 s / 5 apart
    assert t == sorted(t)


def test_spanning_window_leaves_long_windows_and_the_default_alone():
    from evpose.slam.inertial_ba import spanning_window

    sparse = [_kf(k, 80.0 * k) for k in range(20)]  # 80 ms apart (the landing): 6 keyframes span 0.4 s
    assert [k.id for k in spanning_window(sparse, 6, 0.3, 4)] == list(range(14, 20))
    dense = [_kf(k, 5.0 * k) for k in range(20)]
    assert [k.id for k in spanning_window(dense, 6, 0.0, 4)] == list(range(14, 20))
    few = [_kf(k, 5.0 * k) for k in range(4)]
    assert [k.id for k in spanning_window(few, 6, 0.3, 4)] == [0, 1, 2, 3]
