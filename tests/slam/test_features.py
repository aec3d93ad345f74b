"""Bucketed FAST detection (the event-support test drops isolated noise events and keeps real corners), the KLT track gates and
the removal of the warp's curvature shift."""

import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.features import FrontendTracks, detect_features, has_support, remove_curvature_shift, step_consistent


def _corners_and_noise():
    rng = np.random.default_rng(0)
    xs, ys = [], []
    # Four L-shaped corners, each drawn by many events along its two edges.
    for cx, cy in ((50, 40), (150, 40), (50, 120), (150, 120)):
        s = rng.uniform(0, 25, 400)
        xs += [cx + s[:200], np.full(200, cx) + rng.normal(0, 0.3, 200)]
        ys += [np.full(200, cy) + rng.normal(0, 0.3, 200), cy + s[200:]]
    # Isolated background-activity events.
    xs.append(rng.uniform(10, 230, 60))
    ys.append(rng.uniform(10, 170, 60))
    return np.concatenate(xs), np.concatenate(ys)


def test_support_test_drops_isolated_noise_events_but_keeps_corners():
    x, y = _corners_and_noise()
    img = event_image(x, y, None, 240, 180, 1.0)
    cfg = FeatureConfig()
    plain = detect_features(to_uint8(img), cfg)
    cfg.min_support_ratio = 3.0
    supported = detect_features(to_uint8(img), cfg, support=img)
    near_corner = lambda p: min(np.hypot(p[0] - cx, p[1] - cy) for cx, cy in ((50, 40), (150, 40), (50, 120), (150, 120))) < 4
    assert sum(not near_corner(p) for p in supported) < sum(not near_corner(p) for p in plain)
    assert sum(near_corner(p) for p in supported) >= 4
    # Without a support image (or with the ratio at 0) the test is off.
    assert np.array_equal(detect_features(to_uint8(img), cfg), plain)


def _blobs(seed: int, n: int = 60, w: int = 120, h: int = 90) -> np.ndarray:
    """A blob image like an MCI of point features (Gaussian splats)."""
    import cv2

    rng = np.random.default_rng(seed)
    img = np.zeros((h, w), np.float32)
    for x, y in zip(rng.uniform(10, w - 10, n), rng.uniform(10, h - 10, n)):
        img[int(y), int(x)] += 1.0
    img = cv2.GaussianBlur(img, (0, 0), 1.5)
    return to_uint8(img / img.max())


def test_patch_ncc_is_one_for_the_same_patch_and_low_for_another_scene():
    from evpose.slam.features import patch_ncc

    a, b = _blobs(1), _blobs(2)
    uv = np.array([[30.0, 30.0], [60.0, 45.0], [90.0, 60.0], [2.0, 2.0]])
    same = patch_ncc(a, a, uv, uv)
    assert np.allclose(same[:3], 1.0) and same[3] == -1.0  # the last patch leaves the image
    ys, xs = np.nonzero(a > 64)
    pts = np.c_[xs, ys][::7].astype(np.float64)
    assert np.median(patch_ncc(a, b, pts, pts)) < 0.3


def test_min_ncc_drops_tracks_carried_into_another_scene_and_keeps_a_shifted_copy():
    from evpose.slam.features import track_features

    cfg = FeatureConfig()
    a = _blobs(3)
    pts = detect_features(a, cfg).astype(np.float32)
    assert len(pts) >= 10
    shifted = np.roll(a, 2, axis=1)
    new, ok = track_features(a, shifted, pts, cfg, min_ncc=0.6)
    assert ok.mean() > 0.8 and np.allclose(new[ok, 0] - pts[ok, 0], 2.0, atol=0.3)
    other = _blobs(4)
    _, ok_plain = track_features(a, other, pts, cfg, guess=pts)
    _, ok_ncc = track_features(a, other, pts, cfg, guess=pts, min_ncc=0.6)
    # Blob images fool the forward-backward test for a share of tracks; the correlation removes most of those.
    assert ok_plain.sum() >= 10 and ok_ncc.sum() < 0.6 * ok_plain.sum() and ok_ncc.mean() < 0.2


def _steps_with_one_jump():
    rng = np.random.default_rng(3)
    p0 = rng.uniform(20, 220, (40, 2))
    p1 = p0 * 1.02 + np.array([3.0, -2.0])  # a zoom and a shift: one homography
    p1[5] += (4.0, 0.0)  # a new track's first step jumps 4 px
    judge = np.zeros(40, bool)
    judge[[5, 6]] = True  # two new tracks; track 6 moved with the scene
    return p0, p1, judge


def test_first_step_gate_drops_a_new_track_that_left_the_homography_of_the_older_ones():
    p0, p1, judge = _steps_with_one_jump()
    keep = step_consistent(p0, p1, np.ones(40, bool), judge, 3.0)
    assert not keep[5] and keep[6] and keep.sum() == 39


def test_first_step_gate_judges_nothing_with_too_few_tracks():
    p0, p1, judge = _steps_with_one_jump()
    ok = np.zeros(40, bool)
    ok[:8] = True
    assert step_consistent(p0, p1, ok, judge, 3.0).all()


def _two_steps(turn_rad: float):
    """Three positions of one track 10 ms apart moving 200 px/s, its direction turning by ``turn_rad`` per step."""
    dt, speed = 0.01, 200.0
    d0, d1 = np.array([1.0, 0.0]), np.array([np.cos(turn_rad), np.sin(turn_rad)])
    a = np.array([[100.0, 100.0]], np.float32)
    b = a + np.float32(speed * dt) * d0.astype(np.float32)
    c = b + np.float32(speed * dt) * d1.astype(np.float32)
    return a, b, c, dt


def _correct(a, b, c, dt, **kw):
    ids, ok = np.array([7]), np.ones(1, bool)
    _, motion = remove_curvature_shift(a, b, ok, ids, {}, dt, 0.0, 2 * dt, 1.0, False)
    out, motion = remove_curvature_shift(b, c, ok, ids, motion, dt, dt, 2 * dt, kw.pop("gain", 1.0), kw.pop("perpendicular", False), **kw)
    return out, motion


def test_curvature_shift_leaves_a_straight_track_alone():
    a, b, c, dt = _two_steps(0.0)
    out, motion = _correct(a, b, c, dt)
    assert np.allclose(out, c) and np.allclose(motion[7][1], 0.0)


def test_curvature_shift_moves_a_turning_track_out_of_the_turn_by_the_model():
    a, b, c, dt = _two_steps(0.2)
    out, motion = _correct(a, b, c, dt)
    acc = ((c - b)[0] - (b - a)[0]).astype(np.float64) / dt ** 2
    shift = acc * (2 * dt) ** 2 / 24
    assert np.allclose(out[0], c[0] - shift, atol=1e-5)
    assert out[0, 1] < c[0, 1]  # the track turned towards +y: the MCI showed it too far that way
    assert np.allclose(motion[7][1], shift)


def test_curvature_shift_perpendicular_part_and_clip():
    a, b, c, dt = _two_steps(0.2)
    full, _ = _correct(a, b, c, dt)
    perp, _ = _correct(a, b, c, dt, perpendicular=True)
    u = (c - b)[0] / np.linalg.norm((c - b)[0])
    assert abs(float((perp[0] - c[0]) @ u)) < 1e-5 and abs(float((full[0] - c[0]) @ u)) > 1e-3
    clipped, motion = _correct(a, b, c, dt, max_shift_px=0.05)
    assert np.isclose(np.linalg.norm(motion[7][1]), 0.05) and np.isclose(np.linalg.norm(clipped[0] - c[0]), 0.05, atol=1e-5)


def test_curvature_shift_skips_new_and_dropped_tracks():
    a, b, c, dt = _two_steps(0.2)
    p0, p1 = np.vstack([b, b]), np.vstack([c, c])
    out, motion = remove_curvature_shift(p0, p1, np.array([True, False]), np.array([1, 2]), {2: (np.zeros(2), np.zeros(2))}, dt, dt,
                                         2 * dt, 1.0, False)
    assert np.array_equal(out, p1) and set(motion) == {1} and np.allclose(motion[1][1], 0.0)


def test_frontend_curvature_step_times_the_steps_and_keeps_the_state():
    a, b, c, dt = _two_steps(0.2)
    cfg = FeatureConfig(klt_curvature_gain=1.0)
    fe = FrontendTracks(ids=np.array([7]), uv=a, prev_t=0)
    fe.uv, fe.prev_t = fe.remove_curvature_shift(b, np.ones(1, bool), 10_000, cfg, 0.5), 10_000
    out = fe.remove_curvature_shift(c, np.ones(1, bool), 20_000, cfg, 0.5)
    assert fe.prev_step_s == dt and 7 in fe.motion
    assert np.allclose(out, _correct(a, b, c, dt)[0])


def test_has_support_is_false_on_a_blank_patch_and_true_on_an_edge():
    img = np.zeros((60, 80), np.float32)
    img[30, 10:70] = 3.0  # an edge drawn by 180 events
    img[5, 5] = 1.0  # one background-activity event
    uv = np.array([[40.0, 30.4], [40.0, 45.0], [5.0, 5.0]])
    assert has_support(img, uv, 7, 2.0).tolist() == [True, False, False]
    # The mean mass per 7x7 square is 181 * 49 / 4800 = 1.85 events: a lone event is below one mean, the edge far above.
    assert has_support(img, uv, 7, 0.5).tolist() == [True, False, True]
