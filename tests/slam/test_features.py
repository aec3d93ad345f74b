"""Bucketed FAST detection: the event-support test drops isolated noise events and keeps real corners."""

import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.features import detect_features


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
