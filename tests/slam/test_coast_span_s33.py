"""Session 33's defaults for event-only maps: a coast reads its motion over 60 ms of poses, and a two-view start
accepts 0.45 deg of median parallax (``TrackingConfig.coast_span_s``, ``InitializationConfig.min_parallax_deg``)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import invert_pose
from evpose.slam import SlamConfig
from evpose.slam.config import InitializationConfig
from evpose.slam.event_coasting import event_only_coast_pose
from evpose.slam.initialization import initialize_two_view
from slam_synthetic import circle_map, circle_pose


def test_the_default_coast_span_averages_out_pose_noise_that_the_old_span_carries():
    # PnP poses off by a few millimetres each (the rooms': 0.3-0.5 of a 0.1 s step), MCIs 5 ms apart on the circle.
    span = int(SlamConfig().tracking.coast_span_s * 1e6)
    assert span == 60_000
    errs = {30_000: [], span: []}
    for seed in range(40):
        m = circle_map(40, 5000)
        rng = np.random.default_rng(seed)
        for T in m.traj_T[:-1]:
            T[:3, 3] += rng.normal(0, 0.002, 3)
        t = m.traj_t[-1] + 40_000
        truth = circle_pose(t / 1e6)[:3, 3]
        for s in errs:
            errs[s].append(np.linalg.norm(event_only_coast_pose(m, t, s)[:3, 3] - truth))
    assert np.sqrt(np.mean(np.square(errs[span]))) < 0.7 * np.sqrt(np.mean(np.square(errs[30_000])))


def test_the_default_two_view_start_accepts_a_pair_just_under_half_a_degree_of_parallax():
    rng = np.random.default_rng(0)
    K = np.array([[247.0, 0, 172.5], [0, 247.0, 129.5], [0, 0, 1]])
    X = np.c_[rng.uniform(-2.5, 2.5, 150), rng.uniform(-1.8, 1.8, 150), rng.uniform(2.5, 7.0, 150)]

    def proj(T_wc):
        T_cw = invert_pose(T_wc)
        Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
        return Xc[:, :2] / Xc[:, 2:3] @ K[:2, :2].T + K[:2, 2]

    found = None
    for trial in range(2000):  # the decomposition's parallax jumps with the draw: search the draws for such a pair
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec([0.0, -0.01, 0.0]).as_matrix()
        T[:3, 3] = [rng.uniform(0.07, 0.2), 0.0, 0.0]
        p1, p2 = proj(np.eye(4)) + rng.normal(0, 0.2, (150, 2)), proj(T) + rng.normal(0, 0.2, (150, 2))
        old = initialize_two_view(K, p1, p2, InitializationConfig(min_parallax_deg=0.5))
        if not old.ok and "median parallax" in old.reason and 0.45 <= old.median_parallax_deg < 0.5:
            found = (p1, p2)
            break
    assert found is not None  # a pair the old 0.5 deg floor refused for its parallax alone
    assert initialize_two_view(K, *found, InitializationConfig()).ok
