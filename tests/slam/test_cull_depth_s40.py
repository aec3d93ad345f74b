"""A point slid into a keyframe's camera centre: it stalls the local BA, and ``cull_min_depth_ratio`` culls it."""

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import MapPoint
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.config import TrackingConfig
from evpose.slam.geometry import project
from evpose.slam.local_map import cull_points
from slam_synthetic import sideways_map

K = np.array([[200.0, 0, 120], [0, 200.0, 90], [0, 0, 1]])


def _map(seed=0, n_kf=5, n_pts=60, collapsed=True):
    """Keyframes stepping sideways and forwards before a scene 3-6 units away, points and keyframe 4 a little off;
    with ``collapsed`` one more point sits 1e-5 units in front of keyframe 3's centre."""
    def perturb(k, T):
        if k == n_kf - 1:
            T[:3, 3] += [0.01, -0.005, 0.005]

    # closing on the scene (0.05 units forward per keyframe): the epipoles lie in the images
    m, _, true_T = sideways_map(np.random.default_rng(seed), K, n_kf, n_pts, [0.1, 0.01, 0.05], 0.01, perturb)
    if collapsed:
        # On the baseline from keyframe 2 through keyframe 3's centre: at keyframe 2's epipole, where that view holds
        # nothing of the point's place along the baseline (where the local BA of indoor seed 5 had slid its point 202).
        c2, c3 = m.keyframes[2].T_wc[:3, 3], m.keyframes[3].T_wc[:3, 3]
        Xc = c3 + 1e-5 * (c3 - c2) / np.linalg.norm(c3 - c2)
        obs = {k: project(K, invert_pose(m.keyframes[k].T_wc), Xc[None])[0][0] for k in (2, 3)}
        m.points[n_pts] = MapPoint(n_pts, Xc, obs, n_pts, 3)
    return m, true_T


def test_a_point_at_a_camera_centre_stalls_the_local_ba():
    # The collapsed point's Jacobian (pixels per map unit ~ f / 1e-5) makes the normal equations singular: LM finds no
    # step at any lambda and the map stays as it was (final error = initial error), while without it LM converges.
    stuck, _ = _map()
    rep = local_bundle_adjustment(stuck, K, window=5, iterations=10, huber_px=2.0, n_fixed=2)
    assert rep.points > 0 and rep.final_error == rep.initial_error
    clean, _ = _map(collapsed=False)
    rep = local_bundle_adjustment(clean, K, window=5, iterations=10, huber_px=2.0, n_fixed=2)
    assert rep.final_error < 0.5 * rep.initial_error


def test_cull_min_depth_ratio_removes_only_the_collapsed_point():
    m, _ = _map()
    n = len(m.points)
    collapsed = max(m.points)
    track_to_point = {p.track_id: pid for pid, p in m.points.items()}
    # Off (0): the collapsed point is in front of its keyframes and reprojects exactly, so the culling keeps it.
    assert cull_points(m, K, dict(track_to_point), TrackingConfig(), min_depth_ratio=0.0) == 0
    assert cull_points(m, K, track_to_point, TrackingConfig(), min_depth_ratio=0.01) == 1
    assert collapsed not in m.points and len(m.points) == n - 1
    assert collapsed not in track_to_point.values()
    # With it gone the local BA moves again.
    rep = local_bundle_adjustment(m, K, window=5, iterations=10, huber_px=2.0, n_fixed=2)
    assert rep.final_error < 0.5 * rep.initial_error


def test_cull_min_depth_ratio_is_off_by_default():
    # Measured chaotic on the simulated seeds (the field's docstring): an option, not a default.
    assert TrackingConfig().cull_min_depth_ratio == 0.0
