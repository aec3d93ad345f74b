"""Simulated IMU against the ground truth it came from."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.sim.imu_model import GRAVITY_W, ImuConfig, simulate_imu
from evpose.sim.scenarios import SCENARIOS
from evpose.sim.simulator import _rotated_extrinsic
from evpose.sim.trajectories import RigTrajectory


def _setup(scenario="landing_rotation", noise_free=True, seconds=1.0):
    T_ci = _rotated_extrinsic()
    traj = RigTrajectory(SCENARIOS[scenario].trajectory, seconds, T_ci)
    imu = simulate_imu(traj, ImuConfig(rate_hz=1000, noise_free=noise_free), 0, int(seconds * 1e6), np.random.default_rng(0))
    gt = traj.ground_truth(np.arange(0, int(seconds * 1e6) + 1, 1000, dtype=np.int64))
    T_wb = gt.matrices() @ T_ci  # ground truth is the camera; the IMU is the body
    return imu, gt, T_wb


def test_integrating_noise_free_gyro_reproduces_ground_truth_rotation():
    imu, gt, T_wb = _setup()
    R = Rotation.from_matrix(T_wb[0, :3, :3])
    dt = np.diff(imu.samples.t) * 1e-6
    w = imu.samples.gyro
    for k in range(len(dt)):
        R = R * Rotation.from_rotvec(0.5 * (w[k] + w[k + 1]) * dt[k])
    err = (Rotation.from_matrix(T_wb[-1, :3, :3]).inv() * R).magnitude()
    assert np.rad2deg(err) < 0.1
    assert np.rad2deg(np.linalg.norm(w, axis=1)).max() > 60  # the scenario really rotates fast


def test_integrating_noise_free_imu_reproduces_ground_truth_position():
    imu, gt, T_wb = _setup()
    p = T_wb[0, :3, 3].copy()
    v = (-3 * T_wb[0, :3, 3] + 4 * T_wb[1, :3, 3] - T_wb[2, :3, 3]) / 2e-3  # second-order one-sided difference
    R = Rotation.from_matrix(T_wb[:, :3, :3])
    a_w = R.apply(imu.samples.acc) + GRAVITY_W
    for k in range(len(a_w) - 1):
        a = 0.5 * (a_w[k] + a_w[k + 1])
        p = p + v * 1e-3 + 0.5 * a * 1e-6
        v = v + a * 1e-3
    assert np.linalg.norm(p - T_wb[-1, :3, 3]) < 0.01


def test_specific_force_matches_second_derivative_of_position():
    imu, gt, T_wb = _setup(noise_free=True)
    pos = T_wb[:, :3, 3]
    acc_fd = (pos[2:] - 2 * pos[1:-1] + pos[:-2]) / 1e-6
    R = Rotation.from_matrix(T_wb[1:-1, :3, :3])
    f_fd = R.inv().apply(acc_fd - GRAVITY_W)
    assert np.abs(imu.samples.acc[1:-1] - f_fd).max() < 1e-3

    noisy, _, _ = _setup(noise_free=False)
    resid = noisy.samples.acc[1:-1] - f_fd - noisy.acc_bias[1:-1]
    sigma = ImuConfig().acc_noise_density * np.sqrt(1000)
    assert 0.9 < resid.std() / sigma < 1.1


def test_resting_axis_reads_plus_g_when_level():
    imu, gt, T_wb = _setup("landing_slow")
    # Camera looks down: camera z (= body z for the identity part of the extrinsic) points at the ground.
    up_in_body = Rotation.from_matrix(T_wb[:, :3, :3]).inv().apply([0.0, 0.0, 1.0])
    specific_up = np.einsum("ij,ij->i", imu.samples.acc, up_in_body)
    assert abs(np.median(specific_up) - 9.81) < 1.5
