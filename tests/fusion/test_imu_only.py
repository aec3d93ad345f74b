"""IMU-only dead reckoning and the common backend protocol."""

import numpy as np
import pytest

from evpose.fusion import FusionBackend, FusionConfig, make_fusion
from evpose.fusion.imu_only import ImuOnlyPropagator

from fusion_helpers import make_motion, pose_errors


def test_dead_reckoning_with_exact_imu_follows_the_truth_and_ignores_registrations(calibration):
    m = make_motion(duration_s=1.0, imu_rate_hz=1000.0)
    f = ImuOnlyPropagator(FusionConfig(), calibration)
    f.add_imu(m.imu())
    t0 = m.config.t0_us
    f.initialize(t0, m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0), m.camera_velocity([t0], calibration.T_cam_imu)[0])
    times = t0 + np.arange(10_000, 1_000_000, 10_000)
    gt = m.camera_trajectory(times, calibration.T_cam_imu)
    wrong = np.eye(4)
    states = [f.update(int(t), wrong, None) for t in times]
    assert all(s.degraded for s in states)
    errs = np.array([pose_errors(s.T_world_cam, gt.matrix(k)) for k, s in enumerate(states)])
    assert errs[:, 0].max() < 1e-3 and np.degrees(errs[:, 1].max()) < 0.01
    v_err = np.linalg.norm(states[-1].velocity_world - m.camera_velocity([times[-1]], calibration.T_cam_imu)[0])
    assert v_err < 2e-3


@pytest.mark.parametrize("backend", list(FusionBackend))
def test_every_backend_speaks_the_same_protocol(backend, calibration):
    m = make_motion(duration_s=0.3, imu_rate_hz=500.0)
    imu = m.imu()
    f = make_fusion(FusionConfig(backend=backend), calibration)
    f.add_imu(imu[:60])
    t0 = m.config.t0_us
    T0 = m.camera_trajectory([t0], calibration.T_cam_imu).matrix(0)
    s = f.initialize(t0, T0)
    assert s.T_world_cam.shape == (4, 4) and s.velocity_world.shape == (3,)
    f.add_imu(imu[40:])  # overlapping chunk, later samples
    snap = f.snapshot()
    gt = m.camera_trajectory([t0 + 10_000, t0 + 20_000], calibration.T_cam_imu)
    a1 = f.update(t0 + 10_000, gt.matrix(0), np.eye(6) * 1e-6)
    a2 = f.update(t0 + 20_000, None, None)
    p = f.predict(t0 + 21_000)
    assert p.t_us == t0 + 21_000 and a2.degraded and p.degraded
    traj = f.imu_rate_poses(t0, t0 + 20_000)
    assert len(traj) == 10 and traj.t[0] == t0
    f.restore(snap)
    b1 = f.update(t0 + 10_000, gt.matrix(0), np.eye(6) * 1e-6)
    assert np.array_equal(a1.T_world_cam, b1.T_world_cam)
