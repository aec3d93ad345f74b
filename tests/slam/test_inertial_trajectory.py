"""MCI poses between keyframes follow a BA's change of the map's scale (event-inertial maps)."""

import numpy as np

from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.inertial_trajectory import carry_relative_scale, keyframe_positions
from slam_synthetic import circle_pose


def _circle_map() -> SlamMap:
    """Keyframes of the circling camera every 20 ms over 0.2 s, an MCI pose every 5 ms referring to the newest one."""
    m = SlamMap(0)
    for k in range(41):
        t_us = k * 5000
        if k % 4 == 0:
            m.keyframes.append(Keyframe(k // 4, t_us, circle_pose(t_us / 1e6)))
        m.add_pose(t_us, circle_pose(t_us / 1e6))
    return m


def _positions(m: SlamMap) -> np.ndarray:
    return m.trajectory().position


def test_a_bundle_adjustment_that_halves_the_scale_takes_the_poses_between_keyframes_along():
    m = _circle_map()
    before = keyframe_positions(m)
    for kf in m.keyframes:  # what a BA sliding along the monocular scale does to the keyframes
        kf.T_wc[:3, 3] *= 0.5
    changed = carry_relative_scale(m, before)
    # Every pose between two keyframes now sits where the halved map puts it (the keyframes' own poses too).
    assert changed == len(m.traj_t)
    truth = np.stack([circle_pose(t / 1e6)[:3, 3] * 0.5 for t in m.traj_t])
    assert np.allclose(_positions(m), truth, atol=1e-12)


def test_without_the_correction_the_poses_between_keyframes_keep_the_old_scale():
    m = _circle_map()
    for kf in m.keyframes:
        kf.T_wc[:3, 3] *= 0.5
    truth = np.stack([circle_pose(t / 1e6)[:3, 3] * 0.5 for t in m.traj_t])
    err = np.linalg.norm(_positions(m) - truth, axis=1)
    # 15 ms after a keyframe a pose stands half of its 18 mm offset too far: the artefact the correction removes.
    assert np.isclose(err.max(), 0.009, atol=2e-4)


def test_keyframes_a_bundle_adjustment_left_alone_leave_their_poses_untouched():
    m = _circle_map()
    rel = [r.copy() for r in m.traj_rel]
    before = keyframe_positions(m)
    assert carry_relative_scale(m, before) == 0
    # A BA moving only the newest keyframes rescales only the poses near them.
    m.keyframes[-1].T_wc[:3, 3] += 0.01
    n = carry_relative_scale(m, before)
    assert 0 < n < len(m.traj_t)
    assert all(np.array_equal(a, b) for a, b in zip(rel[:10], m.traj_rel[:10]))
