import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.config import EventImageConfig, MciConfig
from evpose.slam.event_window import ReconstructionWindow
from evpose.slam.mci import Hypothesis, MciGenerator, MotionPrior, se3_homographies
from evpose.slam.parallax_warp import depth_field, fit_twist, sample_depth, warp_events

K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
W, H = 160, 120
OMEGA, VEL = np.array([0.2, -0.4, 0.3]), np.array([1.5, 0.8, 0.2])


def _project(t_s, X):
    """Pixels of world points ``X`` for a camera at the origin at t=0 moving with OMEGA / VEL in its own frame."""
    out = np.empty((len(X), 2))
    for k, (tt, x) in enumerate(zip(np.broadcast_to(t_s, len(X)), X)):
        R = Rotation.from_rotvec(OMEGA * tt).as_matrix()
        Xc = R.T @ (x - VEL * tt)
        out[k] = Xc[:2] / Xc[2] * K[0, 0] + K[:2, 2]
    return out


def _two_depth_scene(seed=0, n=120):
    """Points on a ground 4 m away and on roofs 2 m away (a building), the left and right halves of the view."""
    rng = np.random.default_rng(seed)
    uv = np.c_[rng.uniform(10, 150, n), rng.uniform(10, 110, n)]
    z = np.where(uv[:, 0] > 80, 2.0, 4.0)
    return (np.c_[uv, np.ones(n)] @ np.linalg.inv(K).T) * z[:, None], uv, z


def test_depth_field_takes_the_nearest_point_depth():
    uv = np.array([[20.0, 30.0], [120.0, 90.0]])
    field = depth_field(uv, np.array([2.0, 5.0]), W, H)
    assert sample_depth(field, np.array([25.0, 110.0]), np.array([35.0, 80.0])).tolist() == [2.0, 5.0]
    assert depth_field(np.array([[-50.0, 10.0]]), np.array([1.0]), W, H) is None


def test_fit_twist_recovers_the_motion_that_moves_tracks_at_two_depths():
    X, uv, z = _two_depth_scene()
    s = 0.04
    cur = _project(s, X)
    xi, residual = fit_twist(K, uv, cur, z)
    assert residual < 1e-3
    assert np.allclose(xi[:3], OMEGA * s, atol=1e-4) and np.allclose(xi[3:], VEL * s, atol=1e-3)


def test_fit_twist_prior_settles_the_rotation_translation_trade_off_of_noisy_tracks():
    # One far plane and 1 px of track noise: sideways translation and rotation move the tracks alike.
    rng = np.random.default_rng(3)
    uv = np.c_[rng.uniform(10, 150, 40), rng.uniform(10, 110, 40)]
    z = np.full(40, 6.0)
    X = (np.c_[uv, np.ones(40)] @ np.linalg.inv(K).T) * z[:, None]
    s = 0.03
    cur = _project(s, X) + rng.normal(0.0, 1.0, (40, 2))
    truth = np.r_[OMEGA, VEL] * s
    free, _ = fit_twist(K, uv, cur, z)
    assert np.array_equal(fit_twist(K, uv, cur, z, prior=truth, prior_weight=0.0)[0], free)
    pulled, _ = fit_twist(K, uv, cur, z, prior=truth, prior_weight=4.0)
    assert np.linalg.norm(pulled - truth) < 0.5 * np.linalg.norm(free - truth)


def test_warp_events_at_one_depth_equals_the_plane_homography():
    rng = np.random.default_rng(2)
    x, y = rng.uniform(0, W, 50), rng.uniform(0, H, 50)
    dts = np.array([0.01, -0.02])
    idx = rng.integers(0, 2, 50)
    u, v = warp_events(K, x, y, np.full(50, 3.0), idx, np.outer(dts, OMEGA), np.outer(dts, VEL))
    Hs = se3_homographies(K, OMEGA, VEL, 3.0, dts)
    q = np.einsum("nij,nj->ni", Hs[idx], np.c_[x, y, np.ones(50)])
    assert np.allclose(u, q[:, 0] / q[:, 2]) and np.allclose(v, q[:, 1] / q[:, 2])


def _events_of_the_points(X, rng, span_us=100_000, per_point=40):
    """Events (sorted timestamps, us; pixel positions) fired at the points ``X`` as the camera moves, each at the
    projection of its millisecond's middle, and the span, us."""
    t = np.sort(rng.integers(0, span_us, len(X) * per_point))
    j = rng.integers(0, len(X), t.size)
    pos = np.empty((t.size, 2))
    for k in np.unique(t // 1000):
        sel = t // 1000 == k
        pos[sel] = _project((k * 1000 + 500) / 1e6, X[j[sel]])
    return t, pos, span_us


def test_parallax_hypothesis_is_sharper_than_one_depth_warps_on_a_two_depth_scene():
    X, uv, z = _two_depth_scene(n=150)
    rng = np.random.default_rng(4)
    t, pos, span_us = _events_of_the_points(X, rng)
    a, b = span_us // 6, 5 * span_us // 6
    ref, cur = _project(a / 1e6, X), _project(b / 1e6, X)
    rw = ReconstructionWindow(t.astype(np.int64), pos[:, 0], pos[:, 1], np.ones(t.size, np.int8), ref.astype(np.float32),
                              cur.astype(np.float32), a, b, 4, 5.0)
    # The map's points as the last pose (t=0) sees them.
    prior = MotionPrior(omega=OMEGA, velocity=VEL, map_depth=3.0, point_uv=uv, point_depth=z)
    cfg = MciConfig(use_parallax=True)
    res = MciGenerator(cfg, EventImageConfig(), K, W, H).generate(rw, prior)
    assert res.hypothesis is Hypothesis.H5_PARALLAX
    assert res.scores["H5"] > 1.1 * max(res.scores[h] for h in ("H1", "H2", "H3"))
    off = MciGenerator(MciConfig(use_parallax=False), EventImageConfig(), K, W, H).generate(rw, prior)
    assert "H5" not in off.scores
    # Without enough map points in view there is no H5.
    few = MotionPrior(omega=OMEGA, velocity=VEL, map_depth=3.0, point_uv=uv[:5], point_depth=z[:5])
    assert "H5" not in MciGenerator(cfg, EventImageConfig(), K, W, H).generate(rw, few).scores
    # The residual gate keeps H5 when its depths explain the tracks better than H2's similarity, and drops it when
    # the map's depths are wrong (swapped between the two halves).
    gated = MciConfig(use_parallax=True, parallax_max_residual_ratio=1.0)
    assert "H5" in MciGenerator(gated, EventImageConfig(), K, W, H).generate(rw, prior).scores
    flat = MotionPrior(omega=OMEGA, velocity=VEL, map_depth=3.0, point_uv=uv, point_depth=np.where(z > 3.0, 2.0, 4.0))
    assert "H5" not in MciGenerator(gated, EventImageConfig(), K, W, H).generate(rw, flat).scores


def test_parallax_whole_window_fits_the_tracks_carried_through_every_tiny_frame():
    X, uv, z = _two_depth_scene(n=150)
    rng = np.random.default_rng(5)
    t, pos, span_us = _events_of_the_points(X, rng)
    a, b = span_us // 2, 5 * span_us // 6
    # The window's own tracks (its second half) are noisy; the carried ones follow the points through six frames.
    ref, cur = _project(a / 1e6, X), _project(b / 1e6, X) + rng.normal(0.0, 4.0, (150, 2))
    rw = ReconstructionWindow(t.astype(np.int64), pos[:, 0], pos[:, 1], np.ones(t.size, np.int8), ref.astype(np.float32),
                              cur.astype(np.float32), a, b, 4, 5.0)
    rw.whole_t_us = np.linspace(0, b, 6).astype(np.int64)
    rw.whole_pts = np.stack([_project(tt / 1e6, X) for tt in rw.whole_t_us]).astype(np.float32)
    prior = MotionPrior(omega=OMEGA, velocity=VEL, map_depth=3.0, point_uv=uv, point_depth=z)
    own = MciGenerator(MciConfig(use_parallax=True, parallax_whole_window=False), EventImageConfig(), K, W, H).generate(rw, prior)
    whole = MciGenerator(MciConfig(use_parallax=True, parallax_whole_window=True), EventImageConfig(), K, W, H).generate(rw, prior)
    assert whole.scores["H5"] > 1.1 * own.scores["H5"]
    assert whole.hypothesis is Hypothesis.H5_PARALLAX
    # Fewer carried tracks than whole_window_min_tracks: the window's own tracks again.
    rw.whole_pts = rw.whole_pts[:, :8]
    again = MciGenerator(MciConfig(use_parallax=True), EventImageConfig(), K, W, H).generate(rw, prior)
    assert again.scores["H5"] == own.scores["H5"]
