import numpy as np
from scipy.linalg import expm, logm

from evpose.slam.config import EventImageConfig, MciConfig
from evpose.slam.event_window import ReconstructionWindow
from evpose.slam.mci import Hypothesis, MciGenerator, MotionPrior, fit_average_depth, se3_homographies, sim2_homographies

K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
W, H = 160, 120


def _sim2_window(seed=0, n_pts=60, per_pt=40, span_us=40_000):
    """Points moving under a constant Sim(2) velocity; tracks at 1/6 and 5/6 of the window."""
    rng = np.random.default_rng(seed)
    p0 = np.c_[rng.uniform(20, 140, n_pts), rng.uniform(15, 105, n_pts)]
    th, s, tx, ty = 0.08, 1.03, 9.0, -4.0  # motion over the whole window
    M = np.array([[s * np.cos(th), -s * np.sin(th), tx], [s * np.sin(th), s * np.cos(th), ty], [0, 0, 1]])
    L = np.real(logm(M))
    t = np.sort(rng.integers(0, span_us, n_pts * per_pt))
    j = rng.integers(0, n_pts, t.size)
    pos = np.empty((t.size, 2))
    for k in np.unique(t // 1000):
        sel = t // 1000 == k
        A = expm(L * (k * 1000 + 500) / span_us)
        pos[sel] = (np.c_[p0[j[sel]], np.ones(sel.sum())] @ A.T)[:, :2]
    a, b = span_us // 6, 5 * span_us // 6
    ref = (np.c_[p0, np.ones(n_pts)] @ expm(L * a / span_us).T)[:, :2]
    cur = (np.c_[p0, np.ones(n_pts)] @ expm(L * b / span_us).T)[:, :2]
    return ReconstructionWindow(t.astype(np.int64), pos[:, 0], pos[:, 1], np.ones(t.size, np.int8), ref.astype(np.float32), cur.astype(np.float32), a, b, 4, 5.0)


def test_sim2_homographies_equal_matrix_exponential():
    M = np.array([[1.02 * np.cos(0.1), -1.02 * np.sin(0.1), 4.0], [1.02 * np.sin(0.1), 1.02 * np.cos(0.1), -2.0], [0, 0, 1]])
    L = np.real(logm(M))
    for dt, h in zip([0.1, 0.5, 2.0], sim2_homographies(M, 1.0, np.array([0.1, 0.5, 2.0]))):
        assert np.abs(h - expm(L * dt)).max() < 1e-9


def test_mci_selects_sim2_warp_when_features_move_rigidly_in_the_image():
    rw = _sim2_window()
    gen = MciGenerator(MciConfig(), EventImageConfig(), K, W, H)
    res = gen.generate(rw, MotionPrior())
    assert res.hypothesis is Hypothesis.H2_SIM2
    assert res.scores["H2"] == max(res.scores.values())
    assert res.scores["H2"] > 1.3 * res.scores["H4"]
    assert res.image.shape == (H, W) and res.image8.dtype == np.uint8


def _rotation_window(omega, seed=1, span_us=30_000, n_pts=80, per_pt=40):
    """A camera rotating at ``omega`` (own frame, rad/s) in front of a plane 4 m away."""
    rng = np.random.default_rng(seed)
    X = np.c_[rng.uniform(-2, 2, n_pts), rng.uniform(-1.5, 1.5, n_pts), np.full(n_pts, 4.0)]
    t = np.sort(rng.integers(0, span_us, n_pts * per_pt))
    j = rng.integers(0, n_pts, t.size)
    from scipy.spatial.transform import Rotation

    def proj(tt, idx):
        R = Rotation.from_rotvec(np.outer(tt / 1e6, omega)).as_matrix()  # R_wc(t)
        Xc = np.einsum("nji,nj->ni", R, X[idx])  # R^T X
        uv = Xc[:, :2] / Xc[:, 2:3] * 150.0 + [80, 60]
        return uv

    pos = proj(t.astype(float), j)
    # Tracks that are too few and noisy for a good Sim(2) fit: the IMU prior must win.
    a, b = span_us // 6, 5 * span_us // 6
    ref = proj(np.full(4, float(a)), np.arange(4)) + rng.normal(0, 3, (4, 2))
    cur = proj(np.full(4, float(b)), np.arange(4)) + rng.normal(0, 3, (4, 2))
    return ReconstructionWindow(t.astype(np.int64), pos[:, 0], pos[:, 1], np.ones(t.size, np.int8), ref.astype(np.float32), cur.astype(np.float32), a, b, 4, 5.0)


def test_mci_selects_imu_rotation_prior_over_no_compensation_and_wrong_prior():
    omega = np.array([0.3, 1.2, 0.2])
    rw = _rotation_window(omega)
    gen = MciGenerator(MciConfig(use_feature_fit=False), EventImageConfig(), K, W, H)
    good = gen.generate(rw, MotionPrior(omega=omega, velocity=np.zeros(3)))
    assert good.hypothesis is Hypothesis.H3_POSE_PRIOR
    assert good.scores["H3"] > 1.3 * good.scores["H4"]
    wrong = gen.generate(rw, MotionPrior(omega=-omega, velocity=np.zeros(3)))
    assert wrong.scores["H3"] < good.scores["H3"]
    # A wrong prior is not dispatched when the plain histogram is sharper.
    assert wrong.hypothesis is Hypothesis.H4_NONE


def test_fit_average_depth_recovers_plane_depth():
    rng = np.random.default_rng(3)
    X = np.c_[rng.uniform(-1, 1, 30), rng.uniform(-1, 1, 30), np.full(30, 2.5)]
    v, omega, sec = np.array([0.6, 0.1, 0.05]), np.array([0.0, 0.1, 0.0]), 0.05
    ref = X[:, :2] / X[:, 2:3] @ K[:2, :2].T + K[:2, 2]
    Hm = se3_homographies(K, omega, v, 2.5, np.array([sec]))[0]
    q = np.c_[ref, np.ones(30)] @ Hm.T
    cur = q[:, :2] / q[:, 2:3]
    z = fit_average_depth(K, omega, v, ref, cur, sec)
    assert abs(z - 2.5) < 0.05


def _translating_window(velocity_px_s, span_us=40_000, n_pts=30, per_pt=60, seed=3):
    """Points translating at ``velocity_px_s`` in the image; tracks at 1/6 and 5/6 of the window. Returns (window, start positions)."""
    rng = np.random.default_rng(seed)
    p0 = np.c_[rng.uniform(30, 130, n_pts), rng.uniform(25, 95, n_pts)]
    t = np.sort(rng.integers(0, span_us, n_pts * per_pt))
    j = rng.integers(0, n_pts, t.size)
    pos = p0[j] + np.outer(t / 1e6, velocity_px_s)
    a, b = span_us // 6, 5 * span_us // 6
    ref, cur = p0 + velocity_px_s * a / 1e6, p0 + velocity_px_s * b / 1e6
    rw = ReconstructionWindow(t.astype(np.int64), pos[:, 0], pos[:, 1], np.ones(t.size, np.int8), ref.astype(np.float32), cur.astype(np.float32), a, b, 4, 5.0)
    return rw, p0


def test_mci_reference_fraction_warps_events_to_that_time_and_stamps_it():
    v = np.array([200.0, -100.0])  # px/s: 8 px and -4 px over the window
    rw, p0 = _translating_window(v)
    t0, t1 = int(rw.t[0]), int(rw.t[-1])
    for frac in (1.0, 0.5):
        res = MciGenerator(MciConfig(reference_fraction=frac, use_pose_prior=False, use_map_depth=False), EventImageConfig(), K, W, H).generate(rw)
        assert res.hypothesis is Hypothesis.H2_SIM2
        t_ref = t1 if frac == 1.0 else t0 + round(frac * (t1 - t0))
        assert res.t_us == t_ref
        # Each point is sharp where it was at the reference time (the image's peak near it, to a fraction of a pixel).
        expect = p0 + v * t_ref / 1e6
        errs = []
        for u, w in expect:
            iu, iv = int(round(u)), int(round(w))
            patch = res.image[iv - 3:iv + 4, iu - 3:iu + 4].astype(np.float64)
            yy, xx = np.mgrid[-3:4, -3:4]
            c = np.array([(patch * xx).sum(), (patch * yy).sum()]) / patch.sum() + [iu, iv]
            errs.append(np.linalg.norm(c - [u, w]))
        assert np.median(errs) < 0.3


def test_a_wrong_warp_rate_blurs_a_mid_window_mci_in_place_but_shifts_an_end_window_one():
    # Tracks that under-report the motion by a quarter (as a warp model that misses part of the flow would): warped to
    # the window's end, every event lands short of where its point is then, one way; warped to the middle, the errors
    # of early and late events cancel.
    v = np.array([200.0, -100.0])  # px/s: 8 px and -4 px over the window
    rw, p0 = _translating_window(v)
    rw.cur_pts = (rw.ref_pts + 0.75 * (rw.cur_pts - rw.ref_pts)).astype(np.float32)
    t0, t1 = int(rw.t[0]), int(rw.t[-1])
    offsets = {}
    for frac in (1.0, 0.5):
        res = MciGenerator(MciConfig(reference_fraction=frac, use_pose_prior=False, use_map_depth=False), EventImageConfig(), K, W, H).generate(rw)
        expect = p0 + v * res.t_us / 1e6
        errs = []
        for u, w in expect:
            iu, iv = int(round(u)), int(round(w))
            patch = res.image[iv - 4:iv + 5, iu - 4:iu + 5].astype(np.float64)
            yy, xx = np.mgrid[-4:5, -4:5]
            c = np.array([(patch * xx).sum(), (patch * yy).sum()]) / patch.sum() + [iu, iv]
            errs.append(np.linalg.norm(c - [u, w]))
        offsets[frac] = float(np.median(errs))
    assert t0 < t1
    assert offsets[1.0] > 0.7  # a quarter of 8.9 px over half the window: about 1.1 px
    assert offsets[0.5] < 0.35


def test_sim2_whole_window_fits_the_tracks_carried_from_the_window_start():
    rw = _sim2_window(seed=3)
    # The window's own tracks are short and noisy; tracks carried through the whole window follow the true motion.
    rng = np.random.default_rng(4)
    rw.cur_pts = (rw.ref_pts + (rw.cur_pts - rw.ref_pts) * 0.6 + rng.normal(0, 1.0, rw.ref_pts.shape)).astype(np.float32)
    th, s, tx, ty, span = 0.08, 1.03, 9.0, -4.0, 40_000
    L = np.real(logm(np.array([[s * np.cos(th), -s * np.sin(th), tx], [s * np.sin(th), s * np.cos(th), ty], [0, 0, 1]])))
    p0 = np.c_[rng.uniform(20, 140, 40), rng.uniform(15, 105, 40), np.ones(40)]
    rw.whole_t_us = np.array([1_000, 12_000, 25_000, 38_000], np.int64)
    rw.whole_pts = np.stack([(p0 @ expm(L * t / span).T)[:, :2] for t in rw.whole_t_us]).astype(np.float32)
    own = MciGenerator(MciConfig(), EventImageConfig(), K, W, H).generate(rw, MotionPrior())
    whole = MciGenerator(MciConfig(sim2_whole_window=True), EventImageConfig(), K, W, H).generate(rw, MotionPrior())
    truth = expm(L * (38_000 - 1_000) / span)
    assert np.abs(whole.sim2 - truth).max() < 1e-3 < np.abs(own.sim2 - truth).max()
    assert whole.scores["H2"] > own.scores["H2"]
    # Too few carried tracks: the window's own tracks again.
    rw.whole_pts = rw.whole_pts[:, :5]
    again = MciGenerator(MciConfig(sim2_whole_window=True), EventImageConfig(), K, W, H).generate(rw, MotionPrior())
    assert np.array_equal(again.sim2, own.sim2)
