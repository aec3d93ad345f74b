"""Maps of the atlas: the refined trajectory carries per-MCI poses along with their keyframe's later corrections."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.gyro_prior import reanchor_rotations
from slam_synthetic import make_recording


def _pose(rotvec, t):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    T[:3, 3] = t
    return T


def test_refined_trajectory_follows_a_keyframe_moved_by_bundle_adjustment():
    m = SlamMap(0)
    m.keyframes.append(Keyframe(0, 0, np.eye(4)))
    m.add_pose(0, np.eye(4))
    m.add_pose(10, _pose([0, 0.01, 0], [0.1, 0, 0]))
    moved = _pose([0.02, 0, 0], [0, 0.05, 0])
    m.keyframes[0].T_wc = moved  # a later BA moves the reference keyframe
    online, refined = m.trajectory(refined=False).matrices(), m.trajectory().matrices()
    assert np.allclose(online[1], _pose([0, 0.01, 0], [0.1, 0, 0]))
    assert np.allclose(refined[1], moved @ _pose([0, 0.01, 0], [0.1, 0, 0]))
    assert np.allclose(refined[0], moved)


def test_a_similarity_transform_of_the_map_keeps_refined_and_online_poses_equal():
    m = SlamMap(0)
    m.keyframes.append(Keyframe(0, 0, _pose([0.1, 0, 0], [1, 2, 3])))
    m.add_pose(5, _pose([0.1, 0.05, 0], [1.5, 2, 3]))
    m.transform(Rotation.from_rotvec([0, 0, 0.3]).as_matrix(), 2.5)
    assert np.allclose(m.trajectory().matrices(), m.trajectory(refined=False).matrices())


def test_reanchoring_takes_mci_rotations_relative_to_their_keyframe_from_the_gyro():
    rec = make_recording(duration_s=0.5, speed=1.0, seed=2, shake=0.05)
    T = rec.ground_truth.matrices()
    m = SlamMap(0)
    m.keyframes.append(Keyframe(0, int(rec.ground_truth.t[100]), T[100].copy()))
    for k in (100, 150, 200):
        noisy = T[k].copy()
        noisy[:3, :3] = Rotation.from_rotvec([0.01, -0.01, 0.005]).as_matrix() @ noisy[:3, :3]
        m.add_pose(int(rec.ground_truth.t[k]), noisy if k != 100 else T[k])
    reanchor_rotations(m, rec.imu, np.eye(4), 0, np.array([0.004, -0.003, 0.002]))
    out = m.trajectory().matrices()
    for j, k in enumerate((100, 150, 200)):
        assert np.degrees(Rotation.from_matrix(out[j][:3, :3].T @ T[k][:3, :3]).magnitude()) < 1e-5
