"""Gyro rotation priors: integration of the gyro between two times and the pose refinement that uses it."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam.geometry import project
from evpose.slam.gyro_prior import camera_delta_rotation, gyro_delta_rotation, refine_pose_with_rotation_prior
from slam_synthetic import make_recording

K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])


@pytest.fixture(scope="module")
def rec():
    return make_recording(duration_s=0.6, speed=1.0, seed=3, shake=0.05)


def test_gyro_rotation_between_two_times_matches_ground_truth_once_the_bias_is_removed(rec):
    T = rec.ground_truth.matrices()
    i, j = 100, 350
    dR = gyro_delta_rotation(rec.imu, int(rec.ground_truth.t[i]), int(rec.ground_truth.t[j]), np.array([0.004, -0.003, 0.002]))
    truth = T[i][:3, :3].T @ T[j][:3, :3]
    assert np.degrees(Rotation.from_matrix(dR.T @ truth).magnitude()) < 1e-6
    biased = gyro_delta_rotation(rec.imu, int(rec.ground_truth.t[i]), int(rec.ground_truth.t[j]))
    assert np.degrees(Rotation.from_matrix(biased.T @ truth).magnitude()) > 0.05  # the bias shows over 0.25 s


def test_gyro_rotation_outside_the_imu_samples_is_none(rec):
    assert gyro_delta_rotation(rec.imu, -1000, 1000) is None
    assert gyro_delta_rotation(rec.imu, 2000, 1000) is None


def test_camera_rotation_conjugates_the_body_rotation_by_the_extrinsic():
    R_cb = Rotation.from_rotvec([0.0, 0.0, np.pi / 2]).as_matrix()
    T_cb = np.eye(4)
    T_cb[:3, :3] = R_cb
    R_b = Rotation.from_rotvec([0.1, 0.0, 0.0]).as_matrix()  # about the body x axis
    R_c = camera_delta_rotation(R_b, T_cb)
    assert Rotation.from_matrix(R_c).as_rotvec() == pytest.approx([0.0, 0.1, 0.0], abs=1e-12)


def _planar_scene(seed=0):
    rng = np.random.default_rng(seed)
    Xw = np.c_[rng.uniform(-2, 2, 60), rng.uniform(-1.5, 1.5, 60), np.full(60, 5.0)]
    T_wc = np.eye(4)
    T_wc[:3, :3] = Rotation.from_rotvec([0.02, -0.03, 0.01]).as_matrix()
    T_wc[:3, 3] = [0.1, -0.05, 0.2]
    return Xw, T_wc


def test_refinement_converges_to_the_true_pose_from_a_perturbed_start():
    Xw, T_wc = _planar_scene()
    T_cw = invert_pose(T_wc)
    uv, _ = project(K, T_cw, Xw)
    start = T_cw.copy()
    start[:3, :3] = Rotation.from_rotvec([0.01, 0.01, -0.01]).as_matrix() @ start[:3, :3]
    start[:3, 3] += [0.05, -0.03, 0.02]
    out = refine_pose_with_rotation_prior(K, Xw, uv, start, T_cw[:3, :3], sigma_rot_rad=np.radians(0.05), iterations=15)
    assert np.abs(out - T_cw).max() < 1e-4  # 0.006 deg and 0.1 mm: IRLS with Huber weights converges linearly


def test_a_tight_prior_fixes_the_tilt_that_noisy_pixels_on_a_plane_leave_open():
    Xw, T_wc = _planar_scene(1)
    T_cw = invert_pose(T_wc)
    uv, _ = project(K, T_cw, Xw)
    uv = uv + np.random.default_rng(2).normal(0, 1.0, uv.shape)
    loose = refine_pose_with_rotation_prior(K, Xw, uv, T_cw, T_cw[:3, :3], sigma_rot_rad=10.0, iterations=15)
    tight = refine_pose_with_rotation_prior(K, Xw, uv, T_cw, T_cw[:3, :3], sigma_rot_rad=np.radians(0.01), iterations=15)

    def rot_err(T):
        return np.degrees(Rotation.from_matrix(T[:3, :3] @ T_cw[:3, :3].T).magnitude())

    assert rot_err(tight) < 0.02 < rot_err(loose)


def test_klt_start_from_the_gyro_moves_features_as_the_camera_rotation_moves_distant_points(rec):
    from evpose.slam import EventSlam, SlamConfig, SlamMode

    slam = EventSlam(SlamConfig(mode=SlamMode.EVENT_INERTIAL), rec.calibration, rec.imu)
    slam.atlas.new_map()
    T = rec.ground_truth.matrices()
    i, j = 100, 180
    uv = np.array([[20.0, 30.0], [120.0, 90.0], [200.0, 150.0]])
    # Distant points: only the rotation moves them; the synthetic gyro's bias is known here, so remove it.
    m = slam.atlas.active
    m.imu_initialised = True
    m.inertial = type("S", (), {"bias_gyro": np.array([0.004, -0.003, 0.002])})()
    pred = slam._gyro_flow(int(rec.ground_truth.t[i]), int(rec.ground_truth.t[j]), uv)
    R_c0c1 = T[i][:3, :3].T @ T[j][:3, :3]
    d1 = (np.c_[uv, np.ones(3)] @ np.linalg.inv(K).T) @ R_c0c1  # R^T d, row-wise
    truth = (d1 @ K.T)[:, :2] / (d1 @ K.T)[:, 2:3]
    assert np.abs(pred - truth).max() < 1e-3
    assert np.abs(pred - uv).max() > 0.5  # the camera did rotate
    slam.cfg.inertial.klt_gyro_prediction = False
    assert slam._gyro_flow(int(rec.ground_truth.t[i]), int(rec.ground_truth.t[j]), uv) is None


def _disagreeing_pose(rec, initialised: bool, limit_deg: float):
    from evpose.slam import EventSlam, SlamConfig, SlamMode
    from evpose.slam.tracking import PoseEstimate

    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    cfg.inertial.max_gyro_disagreement_deg = limit_deg
    slam = EventSlam(cfg, rec.calibration, rec.imu)
    slam.atlas.new_map().imu_initialised = initialised
    # Depths from 2 to 8: a translation cannot stand in for the rotation, as it could on a plane.
    rng = np.random.default_rng(3)
    Xw = np.c_[rng.uniform(-2, 2, 60), rng.uniform(-1.5, 1.5, 60), rng.uniform(2.0, 8.0, 60)]
    T_wc = np.eye(4)
    uv, _ = project(K, invert_pose(T_wc), Xw)
    est = PoseEstimate(True, T_wc, np.ones(len(Xw), bool), rms_px=0.0)
    R_prior = Rotation.from_rotvec([0.0, np.radians(5.0), 0.0]).as_matrix() @ T_wc[:3, :3]
    return est, slam._refine_with_gyro(est, Xw, uv, R_prior, sigma_deg=0.01)


def test_a_visual_pose_degrees_off_the_gyro_fails_tracking_before_the_imu_initialisation(rec):
    _, out = _disagreeing_pose(rec, initialised=False, limit_deg=2.0)
    assert not out.ok and "off the gyro" in out.reason


def test_the_visual_pose_is_kept_once_initialised_or_with_the_check_off(rec):
    for initialised, limit in ((True, 2.0), (False, 0.0)):
        est, out = _disagreeing_pose(rec, initialised, limit)
        assert out is est


def test_sparse_pair_sigmas_loosen_only_pairs_with_a_sparsely_observed_keyframe():
    from evpose.slam.atlas import MapPoint, SlamMap
    from evpose.slam.gyro_prior import sparse_pair_sigmas

    m = SlamMap(0)
    # Keyframes 0 and 1 see 5 points each, keyframe 2 sees 2.
    for j in range(5):
        obs = {0: np.zeros(2), 1: np.zeros(2)} | ({2: np.zeros(2)} if j < 2 else {})
        m.points[j] = MapPoint(j, np.zeros(3), obs, j, 1)
    priors = {(0, 1): np.eye(3), (1, 2): np.eye(3)}
    assert sparse_pair_sigmas(m, priors, 3, 0.01) == {(1, 2): 0.01}
    assert sparse_pair_sigmas(m, priors, 2, 0.01) == {}
    assert sparse_pair_sigmas(m, priors, 6, 0.01) == {(0, 1): 0.01, (1, 2): 0.01}
