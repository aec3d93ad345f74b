"""The translation direction's uncertainty of a gyro-resolved two-view start
(:func:`evpose.slam.gyro_two_view.translation_direction_std_deg`, ``InertialConfig.init_gyro_two_view_max_direction_std_deg``):
it predicts the direction's actual scatter, tightens with more matches and wider baselines, and gates the start in place of
the parallax bar."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.config import InitializationConfig
from evpose.slam.gyro_two_view import refine_with_gyro_prior, translation_direction_ransac, translation_direction_std_deg, two_view_with_rotation

K = np.array([[200.0, 0.0, 120.0], [0.0, 200.0, 90.0], [0.0, 0.0, 1.0]])
R_WC2 = Rotation.from_rotvec([0.01, -0.03, 0.02]).as_matrix()


def _scene(n: int, baseline, noise_px: float, seed: int = 3):
    """``n`` points 2-4 m away over the whole image, seen from the origin and from a camera at ``baseline`` turned by
    ``R_WC2``; returns the matches, the true unit translation of ``x2 = R x1 + t`` and the median parallax, degrees."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(2.0, 4.0, n)]
    c2 = np.asarray(baseline, np.float64)

    def proj(Xc):
        return Xc[:, :2] / Xc[:, 2:] * 200.0 + [120.0, 90.0]

    p1 = proj(X) + rng.normal(0.0, noise_px, (n, 2))
    p2 = proj((X - c2) @ R_WC2) + rng.normal(0.0, noise_px, (n, 2))
    t = -R_WC2.T @ c2
    a, b = X, X - c2
    par = np.degrees(np.arccos(np.clip(np.sum(a * b, 1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1), -1, 1)))
    return p1, p2, (t / np.linalg.norm(t) if np.linalg.norm(t) > 0 else t), float(np.median(par))


def _solve(p1, p2, sigma_rad=np.radians(0.1)):
    t, inl = translation_direction_ransac(K, p1, p2, R_WC2.T, 1.0)
    R, t = refine_with_gyro_prior(K, p1[inl], p2[inl], R_WC2.T, t, 1.0, sigma_rad)
    return R, t, inl


def _angle_deg(a, b) -> float:
    return float(np.degrees(np.arccos(min(1.0, abs(a @ b) / np.linalg.norm(a) / np.linalg.norm(b)))))


def test_the_predicted_std_matches_the_directions_actual_scatter_over_noise_draws():
    errs, stds = [], []
    for s in range(30):
        p1, p2, t_true, _ = _scene(150, (0.08, 0.0, 0.03), 0.5, seed=100 + s)
        R, t, inl = _solve(p1, p2)
        errs.append(_angle_deg(t, t_true))
        stds.append(translation_direction_std_deg(K, p1[inl], p2[inl], R, t, np.radians(0.1)))
    rms = float(np.sqrt(np.mean(np.square(errs))))
    assert 0.5 * rms < np.median(stds) < 2.0 * rms


def _median_std(n, baseline, noise_px):
    out = []
    for s in range(5):
        p1, p2, _, _ = _scene(n, baseline, noise_px, seed=200 + s)
        R, t, inl = _solve(p1, p2)
        out.append(translation_direction_std_deg(K, p1[inl], p2[inl], R, t, np.radians(0.1)))
    return float(np.median(out))


def test_more_matches_and_wider_baselines_tighten_the_direction():
    assert _median_std(150, (0.08, 0.0, 0.03), 0.5) < 0.75 * _median_std(30, (0.08, 0.0, 0.03), 0.5)
    assert _median_std(150, (0.06, 0.0, 0.02), 0.3) < 0.7 * _median_std(150, (0.03, 0.0, 0.01), 0.3)


def test_a_pure_rotation_or_too_few_matches_leave_the_direction_undetermined():
    # The measured epipolar vectors of a pure rotation are noise; taken at face value they would claim 1 / sqrt(n) rad.
    p1, p2, _, _ = _scene(80, (0.0, 0.0, 0.0), 0.3)
    R, t, inl = _solve(p1, p2)
    assert translation_direction_std_deg(K, p1[inl], p2[inl], R, t, np.radians(0.1)) == float("inf")
    q1, q2, _, _ = _scene(150, (0.08, 0.0, 0.03), 0.5)
    R, t, inl = _solve(q1, q2)
    assert np.isfinite(translation_direction_std_deg(K, q1[inl], q2[inl], R, t, np.radians(0.1)))
    assert translation_direction_std_deg(K, q1[:20], q2[:20], R, t, np.radians(0.1)) == float("inf")


def test_the_std_gate_takes_a_well_observed_low_parallax_start_the_parallax_bar_refuses_and_refuses_a_poor_one():
    cfg = InitializationConfig(min_triangulated=12)
    # 400 matches at 0.1 px over about 0.34 deg of parallax: under the 0.4 deg bar, yet the direction is pinned.
    p1, p2, t_true, par = _scene(400, (0.02, 0.0, 0.005), 0.1)
    assert par < 0.4
    bar = two_view_with_rotation(K, p1, p2, R_WC2, cfg, sigma_deg=0.1, min_parallax_deg=0.4)
    assert not bar.ok and "median parallax" in bar.reason
    gated = two_view_with_rotation(K, p1, p2, R_WC2, cfg, sigma_deg=0.1, min_parallax_deg=0.4, max_direction_std_deg=4.0)
    assert gated.ok and gated.direction_std_deg <= 4.0
    assert _angle_deg(-gated.T_wc2[:3, 3], R_WC2 @ t_true) < 2.0 * gated.direction_std_deg  # camera 2's centre
    # A similar parallax through 16 matches at 1 px: the direction is not pinned, the start waits.
    q1, q2, _, par_q = _scene(16, (0.025, 0.0, 0.005), 1.0, seed=4)
    assert par_q < 0.4
    poor = two_view_with_rotation(K, q1, q2, R_WC2, cfg, sigma_deg=0.1, min_parallax_deg=0.4, max_direction_std_deg=4.0)
    assert not poor.ok and "translation direction std inf" in poor.reason
    # Above the bar nothing changes: the std is not even computed.
    r1, r2, _, par_r = _scene(150, (0.08, 0.0, 0.03), 0.5)
    wide = two_view_with_rotation(K, r1, r2, R_WC2, cfg, sigma_deg=0.1, min_parallax_deg=0.4, max_direction_std_deg=4.0)
    assert par_r > 0.4 and wide.ok and np.isnan(wide.direction_std_deg)
