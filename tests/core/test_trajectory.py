"""Trajectory: matrices, inversion, interpolation, validation."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory, invert_pose
from evpose.errors import InputError


def make():
    t = np.array([0, 1_000_000, 2_000_000])
    rot = Rotation.from_euler("z", [[0], [90], [180]], degrees=True)
    return Trajectory.from_arrays(t, [[0, 0, 0], [1, 0, 0], [2, 0, 0]], rot.as_quat())


def test_matrices_round_trip_through_from_matrices():
    tr = make()
    back = Trajectory.from_matrices(tr.t, tr.matrices())
    np.testing.assert_allclose(back.matrices(), tr.matrices(), atol=1e-12)


def test_invert_pose_gives_identity_when_composed():
    T = make().matrices()
    np.testing.assert_allclose(T @ invert_pose(T), np.broadcast_to(np.eye(4), T.shape), atol=1e-12)


def test_interpolate_is_linear_in_position_and_slerp_in_rotation():
    mid = make().interpolate([500_000])
    np.testing.assert_allclose(mid.position[0], [0.5, 0, 0])
    assert Rotation.from_quat(mid.quat_xyzw[0]).as_euler("zyx", degrees=True)[0] == pytest.approx(45.0)


def test_interpolate_clamps_outside_the_span():
    out = make().interpolate([-5, 9_000_000])
    np.testing.assert_allclose(out.position, [[0, 0, 0], [2, 0, 0]])


def test_quaternions_are_normalised():
    tr = Trajectory.from_arrays([0], [[0, 0, 0]], [[0, 0, 0, 2.0]])
    np.testing.assert_allclose(tr.quat_xyzw, [[0, 0, 0, 1.0]])


def test_validate_rejects_non_increasing_time_and_nan():
    with pytest.raises(InputError, match="pose 1"):
        Trajectory.from_arrays([5, 5], np.zeros((2, 3)), [[0, 0, 0, 1]] * 2).validate()
    with pytest.raises(InputError, match="pose 0: NaN"):
        Trajectory.from_arrays([5], [[np.nan, 0, 0]], [[0, 0, 0, 1]]).validate()


def test_infinite_quaternion_is_reported_by_validate_without_numpy_warnings():
    import warnings

    q = np.array([[0.0, 0.0, 0.0, 1.0], [np.inf, 0.0, 0.0, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning printed before the one-line error
        traj = Trajectory.from_arrays(np.array([0, 1]), np.zeros((2, 3)), q)
    with pytest.raises(InputError, match="pose 1: NaN or infinite value"):
        traj.validate()


@pytest.mark.parametrize("q", [[1e300, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
def test_quaternion_that_cannot_be_normalised_is_named_not_a_scipy_traceback(q):
    quats = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))
    quats[1] = q
    traj = Trajectory.from_arrays([0, 1, 2], np.zeros((3, 3)), quats)
    with pytest.raises(InputError, match="gt.txt: pose 1: quaternion has zero length or one beyond the float range"):
        traj.validate("gt.txt")


def test_position_beyond_the_earth_is_named():
    # 1e300 went through evo's alignment with numpy's overflow warnings on stderr and an 'inf' table.
    pos = np.zeros((3, 3))
    pos[2, 0] = 1e12
    traj = Trajectory.from_arrays([0, 1, 2], pos, np.tile([0.0, 0.0, 0.0, 1.0], (3, 1)))
    with pytest.raises(InputError, match=r"gt.txt: pose 2: position \[1000000000000.0, 0.0, 0.0\] is beyond 1e\+07 m \(not metres\?\)"):
        traj.validate("gt.txt")
