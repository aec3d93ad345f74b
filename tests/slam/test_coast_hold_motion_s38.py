"""``TrackingConfig.coast_hold_motion``: an event-only coast holds the motion measured up to the map's last visually
placed pose (:func:`evpose.slam.event_coasting.held_motion_end`), instead of re-reading it over its own coasted poses."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam import SlamConfig
from evpose.slam.coasting import trajectory_span
from evpose.slam.event_coasting import camera_frame_rate, event_only_coast_pose, held_motion_end
from slam_synthetic import circle_map


def _rate_dps(T0, T1, dt_us):
    return np.degrees(np.linalg.norm(Rotation.from_matrix(T0[:3, :3].T @ T1[:3, :3]).as_rotvec())) / dt_us * 1e6


def _coast(m, n, step_us, span_us, hold):
    """Coast ``n`` MCIs ``step_us`` apart past the map's last pose, as the system does (each pose appended)."""
    end = held_motion_end(m.traj_t, m.traj_t[-1]) if hold else -1
    for _ in range(n):
        t = m.traj_t[-1] + step_us
        m.add_pose(t, event_only_coast_pose(m, t, span_us, end))
    return end


def _jerked_map():
    # 5 ms MCIs on the circle (turning about the camera's -y); the last visually placed pose turned 1.5 deg too far (a
    # noisy PnP with few inliers, as landing seed 4's last one before its coast).
    m = circle_map(30, 5000)
    m.traj_T[-1][:3, :3] = m.traj_T[-1][:3, :3] @ Rotation.from_rotvec([0.0, -np.radians(1.5), 0.0]).as_matrix()
    return m


def test_off_by_default():
    assert SlamConfig().tracking.coast_hold_motion is False


def test_held_motion_end_is_the_newest_pose_at_or_before_the_last_visual_time():
    t = [0, 5000, 10000, 15000]
    assert held_motion_end(t, 10000) == 2
    assert held_motion_end(t, 12000) == 2
    assert held_motion_end(t, 20000) == 3
    assert held_motion_end(t, -1) == -1


def test_a_span_ending_at_an_index_reads_only_the_poses_up_to_it():
    m = circle_map(30, 5000)
    assert trajectory_span(m, 60_000) == (17, 60_000)
    assert trajectory_span(m, 60_000, 20) == (8, 60_000)
    assert trajectory_span(m, 60_000, 5) is None  # 25 ms of poses up to index 5
    assert trajectory_span(m, 60_000, -1) == trajectory_span(m, 60_000)


def test_a_held_coast_turns_at_one_rate_while_the_rereading_coast_drifts_off_it():
    span = int(SlamConfig().tracking.coast_span_s * 1e6)
    held, reread = _jerked_map(), _jerked_map()
    k = len(held.traj_t) - 1
    w0 = np.degrees(np.linalg.norm(camera_frame_rate(held, span))) * 1e6  # the rate the coast starts on
    _coast(held, 20, 5000, span, hold=True)
    _coast(reread, 20, 5000, span, hold=False)
    rates_held = [_rate_dps(held.traj_T[j], held.traj_T[j + 1], 5000) for j in range(k, len(held.traj_t) - 1)]
    rates_reread = [_rate_dps(reread.traj_T[j], reread.traj_T[j + 1], 5000) for j in range(k, len(reread.traj_t) - 1)]
    assert np.allclose(rates_held, w0, rtol=1e-6)
    # Re-reading over its own coasted poses, the coast counts the jerk again and again: it settles above the start.
    assert rates_reread[-1] > w0 * 1.02
    assert max(rates_reread) > w0 * 1.05


def test_a_held_coast_ends_nearer_the_truth_than_the_rereading_one():
    span = int(SlamConfig().tracking.coast_span_s * 1e6)
    truth = circle_map(30 + 40, 5000)
    held, reread = _jerked_map(), _jerked_map()
    _coast(held, 40, 5000, span, hold=True)
    _coast(reread, 40, 5000, span, hold=False)

    def rot_err(m):
        return np.degrees(np.linalg.norm(Rotation.from_matrix(truth.traj_T[-1][:3, :3].T @ m.traj_T[-1][:3, :3]).as_rotvec()))
    assert rot_err(held) < rot_err(reread)
    assert np.linalg.norm(held.traj_T[-1][:3, 3] - truth.traj_T[-1][:3, 3]) < np.linalg.norm(reread.traj_T[-1][:3, 3] - truth.traj_T[-1][:3, 3])


def test_without_a_jerk_both_coasts_follow_the_circle_alike():
    span = int(SlamConfig().tracking.coast_span_s * 1e6)
    held, reread = circle_map(30, 5000), circle_map(30, 5000)
    _coast(held, 20, 5000, span, hold=True)
    _coast(reread, 20, 5000, span, hold=False)
    # The same turn; the positions differ only by chord against arc velocity (millimetres after 0.1 s).
    assert np.allclose(held.traj_T[-1][:3, :3], reread.traj_T[-1][:3, :3], atol=1e-9)
    assert np.linalg.norm(held.traj_T[-1][:3, 3] - reread.traj_T[-1][:3, 3]) < 0.01
