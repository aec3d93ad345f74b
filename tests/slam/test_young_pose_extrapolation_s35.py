"""A map's young poses may be read off the motion of its later poses (TrackingConfig.young_pose_extrapolation_s)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.atlas import Atlas, Keyframe
from evpose.slam.config import SlamConfig
from evpose.slam.pose_refit import first_pose_extrapolated
from tests.slam.test_atlas import _pose as _T


def _steady(ts, off):
    """1 unit along x and 0.1 rad about y per 100 us from t = 0; poses at the times in ``off`` displaced by 7 in y, the
    last pose by 0.5 in z (so that no stretch of poses lies on one line)."""
    return [_T([0, 0.001 * t, 0], [0.01 * t, 7.0 * (t in off), 0.5 * (t == ts[-1])]) for t in ts]


def test_every_pose_younger_than_the_limit_follows_the_anchor_s_motion_back_to_its_time():
    ts = [0, 50, 100, 200, 300, 400, 500]
    T = _steady(ts, off={0, 50, 100})
    out = first_pose_extrapolated(ts, T, span_us=200, young_us=150)
    # anchor: the first pose at least 150 us after the first (t = 200), its motion to t = 400 held back
    for k, t in enumerate(ts[:3]):
        assert np.allclose(out[k][:3, 3], [0.01 * t, 0, 0])
        assert np.allclose(Rotation.from_matrix(out[k][:3, :3]).as_rotvec(), [0, 0.001 * t, 0])
    assert all(a is b for a, b in zip(out[3:], T[3:]))


def test_no_young_limit_replaces_the_first_pose_only_as_before():
    ts = [0, 50, 100, 200, 300, 400]
    T = _steady(ts, off={0, 50})
    out = first_pose_extrapolated(ts, T, span_us=200, young_us=0)
    assert np.allclose(out[0], first_pose_extrapolated(ts, T, span_us=200)[0])
    assert all(a is b for a, b in zip(out[1:], T[1:]))  # the displaced second pose stays: it is the anchor


def test_a_map_too_short_for_its_young_stretch_replaces_its_first_pose_only():
    ts = [0, 50, 100, 200]
    T = _steady(ts, off={0})
    out = first_pose_extrapolated(ts, T, span_us=50, young_us=150)  # anchor t = 200 would leave no span after it
    assert np.allclose(out[0][:3, 3], [0, 0, 0]) and all(a is b for a, b in zip(out[1:], T[1:]))


def test_an_anchor_stretch_on_one_line_falls_back_to_the_first_pose():
    # from the anchor on the poses lie on one line (a coast): replacing the young ones would leave them all on it
    ts = [0, 50, 100, 200, 300, 400]
    T = [_T([0, 0, 0], [0.0, 5.0, 0]), _T([0, 0, 0], [0.5, 1.0, 0]), _T([0, 0, 0], [1.0, 0, 0])] + \
        [_T([0, 0, 0], [0.01 * t, 0, 0]) for t in ts[3:]]
    out = first_pose_extrapolated(ts, T, span_us=100, young_us=150)
    assert np.allclose(out[0], first_pose_extrapolated(ts, T, span_us=100)[0])
    assert not np.allclose(out[0], T[0]) and all(a is b for a, b in zip(out[1:], T[1:]))
    # ... and all on one line from the second pose on: nothing moves
    T2 = [T[0]] + [_T([0, 0, 0], [0.01 * t, 0, 0]) for t in ts[1:]]
    assert all(a is b for a, b in zip(first_pose_extrapolated(ts, T2, span_us=100, young_us=150), T2))


def test_the_map_reads_its_young_poses_so_when_set_and_the_option_is_on_by_default():
    cfg = SlamConfig().tracking
    assert cfg.young_pose_extrapolation_s == 0.15 and cfg.first_pose_extrapolation_s == 0.2
    K = np.array([[250.0, 0, 173], [0, 250.0, 130], [0, 0, 1]])
    ts = [0, 50, 100, 200, 300, 400, 500]
    for young_us in (0, 150):
        m = Atlas(refit_K=K, first_pose_span_us=200, young_pose_us=young_us).new_map()
        m.keyframes.append(Keyframe(0, 0, np.eye(4)))
        for t, T in zip(ts, _steady(ts, off={0, 50, 100})):
            m.add_pose(t, T)
        # a PnP-placed pose whose inliers are gone from the map: recorded, not re-solved (too few points)
        m.record_pose_observations(500, np.array([99]), np.zeros((1, 2)), np.zeros(0, np.int64), np.zeros((0, 2)))
        P = m.trajectory().matrices()[:, :3, 3]
        assert np.allclose(P[1:3, 1], 7.0 if young_us == 0 else 0.0)
        assert np.allclose(m.trajectory(refit=False).matrices()[:3, 1, 3], 7.0)  # as the map holds them
