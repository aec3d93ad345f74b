"""A map's first pose may be read off the motion of its next poses (TrackingConfig.first_pose_extrapolation_s, 0.2 s by default)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import Atlas, Keyframe
from evpose.slam.config import SlamConfig
from evpose.slam.pose_refit import first_pose_extrapolated
from tests.slam.test_atlas import _pose as _T


def test_the_first_pose_follows_the_next_poses_motion_back_to_its_time():
    # steady motion of 1 unit and 0.1 rad about y per 100 us from t = 100 on; the first pose at t = 50 is off
    ts = [50, 100, 200, 300]
    T = [_T([0, 0, 0], [7.0, 7.0, 7.0])] + [_T([0, 0.1 * k, 0], [1.0 * k, 0.1 * (k == 1), 0]) for k in range(3)]
    out = first_pose_extrapolated(ts, T, span_us=200)
    assert np.allclose(out[0][:3, 3], [-0.5, 0, 0])
    assert np.allclose(Rotation.from_matrix(out[0][:3, :3]).as_rotvec(), [0, -0.05, 0])
    assert all(np.allclose(a, b) for a, b in zip(out[1:], T[1:]))


def test_a_span_past_the_map_s_end_uses_its_last_pose_and_short_maps_are_kept():
    ts = [0, 10, 20, 30]
    T = [_T([0, 0, 0], [5.0, 0, 0]), _T([0, 0, 0], [1.0, 0, 0]), _T([0, 0, 0], [2.0, 0, 0]), _T([0, 0, 0], [3.0, 1.0, 0])]
    assert np.allclose(first_pose_extrapolated(ts, T, span_us=10_000)[0][:3, 3], [-0.0, -0.5, 0])  # 1 -> 3 over 20 us
    assert np.allclose(first_pose_extrapolated(ts[:3], T[:3], span_us=10)[0], T[0])  # three poses: kept
    assert np.allclose(first_pose_extrapolated(ts, T, span_us=0)[0], T[0])


def test_later_poses_on_one_line_keep_the_first_pose():
    # a coast: the first pose moved onto the line would make the map straight, which no Sim(3) can align
    ts = [0, 10, 20, 30]
    T = [_T([0, 0, 0], [5.0, 1.0, 0])] + [_T([0, 0, 0], [float(k), 0, 0]) for k in (1, 2, 3)]
    assert np.allclose(first_pose_extrapolated(ts, T, span_us=10)[0], T[0])


def _map(span_us: int, pnp_placed: bool):
    K = np.array([[250.0, 0, 173], [0, 250.0, 130], [0, 0, 1]])
    m = Atlas(refit_K=K, first_pose_span_us=span_us).new_map()
    m.keyframes.append(Keyframe(0, 50, _T([0, 0, 0], [3.0, 0, 0])))
    m.add_pose(50, _T([0, 0, 0], [3.0, 0, 0]))
    for k, t in enumerate((100, 200, 300)):
        m.add_pose(t, _T([0, 0, 0], [3.0 + 1.0 * k, 0.25 * (k == 2), 0]))  # composed on the first keyframe
    if pnp_placed:
        # a PnP-placed pose whose inliers are gone from the map: recorded, not re-solved (too few points)
        m.record_pose_observations(300, np.array([99]), np.zeros((1, 2)), np.zeros(0, np.int64), np.zeros((0, 2)))
    return m


def test_the_map_reads_its_first_pose_so_only_when_set_and_the_option_is_on_by_default():
    assert SlamConfig().tracking.first_pose_extrapolation_s == 0.2
    assert np.allclose(_map(0, True).trajectory().matrices()[0][:3, 3], [3.0, 0, 0])
    m = _map(200, True)
    assert np.allclose(m.trajectory().matrices()[0][:3, 3], [2.5, -0.0625, 0])
    assert np.allclose(m.trajectory(refit=False).matrices()[0][:3, 3], [3.0, 0, 0])


def test_a_map_without_pnp_placed_poses_keeps_its_first_pose():
    # a coasted map's poses lie on its held motion: its first pose moved onto that line could leave it exactly straight
    assert np.allclose(_map(200, False).trajectory().matrices()[0][:3, 3], [3.0, 0, 0])
