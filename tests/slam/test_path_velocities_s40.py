"""Keyframe velocities from the map's own path after the IMU initialisation (``InertialWindowConfig.init_velocity_span_s``)."""

import types

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.config import SlamConfig
from evpose.slam.inertial_ba import InertialState
from evpose.slam.inertial_trajectory import path_velocities
from evpose.slam.system_inertial import InertialMaps


def _keyframes(v, n=60, dt_us=5000, jitter=0.0, omega=0.0, coasted=()):
    """Keyframes on a straight path at velocity ``v`` (camera position), yawing at ``omega`` rad/s, with position jitter."""
    rng = np.random.default_rng(1)
    out = []
    for k in range(n):
        t = k * dt_us / 1e6
        T = np.eye(4)
        c, s = np.cos(omega * t), np.sin(omega * t)
        T[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        T[:3, 3] = np.asarray(v) * t + rng.normal(0, jitter, 3)
        if k in coasted:
            T[:3, 3] += 0.5  # a coasted keyframe far off the path
        out.append(Keyframe(k, k * dt_us, T, {}, visual=k not in coasted))
    return out


def test_the_velocity_is_the_slope_of_the_path_not_a_two_keyframe_difference():
    v = np.array([1.2, -0.3, 0.1])
    kfs = _keyframes(v, jitter=0.005)
    got = path_velocities(kfs, np.eye(4), 0.2)
    assert set(got) == {kf.id for kf in kfs}
    err = np.array([np.linalg.norm(got[k] - v) for k in got])
    assert err.max() < 0.25  # 5 mm jitter 5 ms apart: a difference of two neighbours is ~1.4 m/s off
    two = np.linalg.norm(np.diff([kf.T_wc[:3, 3] for kf in kfs], axis=0) / 0.005 - v, axis=1)
    assert np.median(err) < 0.2 * np.median(two)


def test_the_imu_lever_arm_and_coasted_keyframes():
    v = np.array([0.0, 1.0, 0.0])
    T_cb = np.eye(4)
    T_cb[:3, 3] = [0.1, 0.0, 0.0]  # the IMU 10 cm off the camera: a yawing camera moves it at omega x lever
    kfs = _keyframes(v, omega=2.0, coasted={29, 30, 31})
    got = path_velocities(kfs, T_cb, 0.1)
    t = kfs[30].t_us / 1e6
    lever_rate = 2.0 * 0.1 * np.array([-np.sin(2 * t), np.cos(2 * t), 0.0])
    assert np.linalg.norm(got[30] - (v + lever_rate)) < 0.02  # coasted keyframes 0.5 off the path are left out
    assert path_velocities(kfs, T_cb, 0.0) == {}


def test_the_initialisation_hook_sets_the_velocities_only_when_on():
    v = np.array([1.0, 0.0, 0.0])
    for span, want in ((0.0, 0.2), (0.1, 1.0)):
        m = SlamMap(0)
        m.keyframes = _keyframes(v, n=30)
        m.inertial = InertialState({kf.id: 0.2 * v for kf in m.keyframes}, np.zeros(3), np.zeros(3))
        cfg = SlamConfig()
        cfg.inertial.ba_window.init_velocity_span_s = span
        sys_ = types.SimpleNamespace(cfg=cfg, calib=types.SimpleNamespace(T_cam_imu=np.eye(4)))
        InertialMaps._path_velocities(sys_, m)
        assert all(np.allclose(u, want * v) for u in m.inertial.velocities.values())
