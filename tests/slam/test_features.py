"""Bucketed FAST detection (the event-support test drops isolated noise events and keeps real corners), KLT's patch
correlation gate."""

import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.features import detect_features, has_support


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
    from evpose.slam.track_step import patch_ncc

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


def test_has_support_is_false_on_a_blank_patch_and_true_on_an_edge():
    img = np.zeros((60, 80), np.float32)
    img[30, 10:70] = 3.0  # an edge drawn by 180 events
    img[5, 5] = 1.0  # one background-activity event
    uv = np.array([[40.0, 30.4], [40.0, 45.0], [5.0, 5.0]])
    assert has_support(img, uv, 7, 2.0).tolist() == [True, False, False]
    # The mean mass per 7x7 square is 181 * 49 / 4800 = 1.85 events: a lone event is below one mean, the edge far above.
    assert has_support(img, uv, 7, 0.5).tolist() == [True, False, True]
