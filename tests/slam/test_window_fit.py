import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.parallax_warp import fit_twist
from evpose.slam.window_fit import fit_twist_rate, whole_span_s

K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
OMEGA, VEL = np.array([0.2, -0.4, 0.3]), np.array([1.5, 0.8, 0.2])


def _tracks(t_us, n=60, seed=0):
    """Pixels (F, n, 2) of points on a ground 4 m and roofs 2 m away, seen by a camera moving with OMEGA / VEL from t=0."""
    rng = np.random.default_rng(seed)
    uv = np.c_[rng.uniform(10, 150, n), rng.uniform(10, 110, n)]
    z = np.where(uv[:, 0] > 80, 2.0, 4.0)
    X = (np.c_[uv, np.ones(n)] @ np.linalg.inv(K).T) * z[:, None]
    out, depth = [], []
    for t in np.asarray(t_us) / 1e6:
        Xc = (X - VEL * t) @ Rotation.from_rotvec(OMEGA * t).as_matrix()
        out.append(Xc[:, :2] / Xc[:, 2:3] * K[0, 0] + K[:2, 2])
        depth.append(Xc[:, 2])
    return np.stack(out), depth[0]  # depths in the first frame


def test_fit_twist_rate_recovers_the_constant_twist_through_every_frame():
    t_us = np.array([0, 9_000, 20_000, 31_000, 40_000, 52_000])
    pts, z = _tracks(t_us)
    rate, residual = fit_twist_rate(K, pts, t_us, z)
    assert residual < 1e-3
    assert np.allclose(rate[:3], OMEGA, atol=2e-3) and np.allclose(rate[3:], VEL, atol=2e-2)


def test_fit_twist_rate_over_two_frames_is_the_two_view_fit_per_second():
    t_us = np.array([3_000, 43_000])
    pts, z = _tracks(t_us - 3_000, n=30, seed=2)
    pts = pts + np.random.default_rng(1).normal(0.0, 0.7, pts.shape)
    rate, residual = fit_twist_rate(K, pts, t_us, z)
    xi, residual2 = fit_twist(K, pts[0], pts[-1], z)
    assert np.allclose(rate * 0.04, xi, atol=1e-6) and abs(residual - residual2) < 1e-6


def test_fit_twist_rate_refuses_tracks_without_time_or_too_few_points():
    pts, z = _tracks([0, 10_000], n=5)
    assert fit_twist_rate(K, pts, np.array([0, 10_000]), z) is None
    pts, z = _tracks([0, 0], n=20)
    assert fit_twist_rate(K, pts, np.array([0, 0]), z) is None
    assert whole_span_s(np.array([5_000])) == 0.0


def test_a_second_set_of_tracks_with_its_own_frames_joins_the_fit():
    t_us = np.array([0, 10_000, 20_000, 30_000])
    pts, z = _tracks(t_us, n=8, seed=3)
    own_t = np.array([20_000, 45_000])
    own, own_z = _tracks(own_t, n=40, seed=4)
    rate, residual = fit_twist_rate(K, pts, t_us, z, extra=(own, own_t, own_z))
    assert residual < 0.02 and np.allclose(rate, np.r_[OMEGA, VEL], atol=2e-2)
    # The joint fit weighs the second set: with the first set's tracks disturbed it stays nearer the truth.
    noisy = pts + np.random.default_rng(0).normal(0.0, 1.5, pts.shape)
    alone, _ = fit_twist_rate(K, noisy, t_us, z)
    joint, _ = fit_twist_rate(K, noisy, t_us, z, extra=(own, own_t, own_z))
    truth = np.r_[OMEGA, VEL]
    assert np.linalg.norm(joint - truth) < 0.5 * np.linalg.norm(alone - truth)
