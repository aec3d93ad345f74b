"""A written coast can remove the image motion the camera's translation adds to the visual gyro's pure-rotation fit
(``TrackingConfig.coast_written_parallax``, :mod:`evpose.slam.written_coast`)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.config import SlamConfig
from evpose.slam.written_coast import parallax_rotation, written_coast_pose
from slam_synthetic import circle_map, circle_pose


def test_a_sideways_step_reads_as_a_turn_about_the_vertical():
    """A point straight ahead at depth 2, the camera stepping 0.02 along +x: it lands where a turn of 0.01 rad about +y
    puts it (to first order), and that is the rotation returned."""
    rv = parallax_rotation(np.array([4.0, 0.0, 0.0]), 2.0, 0.005)
    np.testing.assert_allclose(rv, (0.0, 0.01, 0.0), atol=1e-15)
    P = np.array([0.0, 0.0, 2.0])
    stepped = P - (0.02, 0.0, 0.0)
    turned = Rotation.from_rotvec(rv).as_matrix().T @ P
    assert abs(stepped[0] / stepped[2] - turned[0] / turned[2]) < 1e-6


def test_default_is_off():
    assert SlamConfig().tracking.coast_written_parallax is False


def test_measured_turn_with_parallax_is_written_as_the_camera_turn():
    """The circling camera (turning 0.75 rad/s, moving 1.2 m/s sideways) before walls 2 m away: a pure-rotation fit reads
    the turn plus the translation's parallax; removing it leaves the circle's own turn."""
    m = circle_map(12, 5000)
    t_prev, dt = m.traj_t[-1], 5000
    R_prev, R_next = circle_pose(t_prev / 1e6)[:3, :3], circle_pose((t_prev + dt) / 1e6)[:3, :3]
    true_rv = Rotation.from_matrix(R_prev.T @ R_next).as_rotvec()
    v_cam = R_prev.T @ (circle_pose((t_prev + dt) / 1e6)[:3, 3] - circle_pose(t_prev / 1e6)[:3, 3]) / dt
    measured = Rotation.from_rotvec(true_rv + parallax_rotation(v_cam, 2.0, dt)).as_matrix()
    T_raw = written_coast_pose(m, t_prev + dt, 30_000, 5000, lambda dR0: measured)
    T = written_coast_pose(m, t_prev + dt, 30_000, 5000, lambda dR0: measured, lambda T_wc: 2.0)
    err = lambda R: np.degrees(Rotation.from_matrix(R.T @ R_next).magnitude())
    assert err(T_raw[:3, :3]) > 0.1  # the parallax, ~0.17 deg over 5 ms
    assert err(T[:3, :3]) < 0.01 * err(T_raw[:3, :3])


def test_parallax_against_the_measured_turn_leaves_the_measurement():
    """A velocity whose parallax would turn the other way (or more than was measured) is the map's error, not the
    scene's: the measured rotation is written as it is."""
    m = circle_map(12, 5000)
    t = m.traj_t[-1] + 5000
    against = Rotation.from_rotvec([0.0, 0.02, 0.0]).as_matrix()  # the circle turns about -y
    T = written_coast_pose(m, t, 30_000, 5000, lambda dR0: against, lambda T_wc: 2.0)
    np.testing.assert_allclose(T[:3, :3], m.traj_T[-1][:3, :3] @ against, atol=1e-12)
    no_depth = written_coast_pose(m, t, 30_000, 5000, lambda dR0: against, lambda T_wc: None)
    np.testing.assert_allclose(no_depth, T, atol=1e-12)


def test_long_velocity_span_holds_the_older_speed_of_a_slowing_map():
    """``coast_written_velocity_span_s``: a map whose last steps shrank to a third coasts its written pose on the
    velocity over the longer span, the rotation rate still over ``coast_span_s``."""
    from evpose.slam.atlas import SlamMap

    m = SlamMap(0)
    x = 0.0
    for k in range(40):  # 5 ms apart: 1 unit/s for 150 ms, then 1/3 unit/s
        x += 0.005 if k <= 30 else 0.005 / 3
        T = np.eye(4)
        T[:3, 3] = (x, 0.0, 0.0)
        m.add_pose(k * 5000, T)
    t = m.traj_t[-1] + 10_000
    short = written_coast_pose(m, t, 30_000, 5000, lambda dR0: None)
    long_ = written_coast_pose(m, t, 30_000, 5000, lambda dR0: None, velocity_span_us=150_000)
    assert abs((short[0, 3] - x) - 0.01 / 3) < 1e-9
    k0 = m.traj_t.index(m.traj_t[-1] - 150_000)
    speed = (x - m.traj_T[k0][0, 3]) / 150_000  # the mean over the newest 150 ms: 21 full steps and 9 shrunk ones
    assert abs((long_[0, 3] - x) - speed * 10_000) < 1e-9 and speed * 10_000 > 2 * 0.01 / 3


def test_span_by_gap_keeps_a_dense_coast_and_lengthens_a_step_across_a_blank():
    from evpose.slam.atlas import SlamMap

    m = SlamMap(0)
    x = 0.0
    for k in range(40):  # as above: the last 9 steps shrank to a third
        x += 0.005 if k <= 30 else 0.005 / 3
        T = np.eye(4)
        T[:3, 3] = (x, 0.0, 0.0)
        m.add_pose(k * 5000, T)
    dense = m.traj_t[-1] + 10_000
    np.testing.assert_allclose(written_coast_pose(m, dense, 30_000, 5000, lambda dR0: None, None, 150_000, True),
                               written_coast_pose(m, dense, 30_000, 5000, lambda dR0: None), atol=1e-15)
    blank = m.traj_t[-1] + 150_000  # across a 150 ms blank: the velocity over the newest 150 ms
    np.testing.assert_allclose(written_coast_pose(m, blank, 30_000, 5000, lambda dR0: None, None, 150_000, True),
                               written_coast_pose(m, blank, 30_000, 5000, lambda dR0: None, None, 150_000), atol=1e-15)
    assert written_coast_pose(m, blank, 30_000, 5000, lambda dR0: None, None, 150_000, True)[0, 3] > \
        written_coast_pose(m, blank, 30_000, 5000, lambda dR0: None)[0, 3] + 0.03


def test_depth_in_view_is_the_median_depth_of_the_points_inside_the_image():
    from evpose.slam.atlas import MapPoint, SlamMap
    from evpose.slam.written_coast import depth_in_view

    K = np.array([[100.0, 0, 50], [0, 100.0, 40], [0, 0, 1]])
    m = SlamMap(0)
    xyz = [(0, 0, 2.0), (0.1, 0, 3.0), (0, 0.1, 4.0), (-0.1, 0, 5.0), (0, -0.1, 6.0),  # in view, depths 2-6
           (5.0, 0, 1.0), (0, 0, -3.0)]  # outside the image, behind the camera
    for k, X in enumerate(xyz):
        m.points[k] = MapPoint(k, np.array(X, float))
    depth = depth_in_view(m, K, (80, 100))
    assert depth(np.eye(4)) == 4.0
    assert depth_in_view(m, K, (80, 100), min_points=6)(np.eye(4)) is None
    T = np.eye(4)
    T[2, 3] = -1.0  # one unit back: every in-view depth grows by one
    assert depth(T) == 5.0
