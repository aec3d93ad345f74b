import cv2
import numpy as np

from evpose.slam.birth_anchor import BirthAnchors
from evpose.slam.feature_config import FeatureConfig


def _blobs(shift: tuple[float, float]) -> np.ndarray:
    img = np.zeros((120, 160), np.float32)
    for u, v in [(40, 40), (100, 50), (70, 90), (120, 85)]:
        cv2.circle(img, (int(u), int(v)), 4, 1.0, -1)
        cv2.rectangle(img, (int(u) + 6, int(v) - 3), (int(u) + 14, int(v) + 3), 0.6, -1)
    img = cv2.GaussianBlur(img, (0, 0), 1.2)
    M = np.float32([[1, 0, shift[0]], [0, 1, shift[1]]])
    return np.clip(cv2.warpAffine(img, M, (160, 120)) * 255, 0, 255).astype(np.uint8)


def test_drifted_track_moves_back_onto_its_birth_point():
    cfg = FeatureConfig(klt_birth_anchor_px=6.0, klt_birth_anchor_min_age=1)
    birth8, cur8 = _blobs((0, 0)), _blobs((5.0, 3.0))
    a = BirthAnchors()
    ids = np.array([7], np.int64)
    a.register(ids, np.array([[40.0, 40.0]], np.float32), birth8)
    drifted = np.array([[48.0, 43.0]], np.float32)  # truth (45, 43): 3 px ahead along the motion
    out, ok = a.anchor(cur8, ids, drifted, np.array([True]), cfg)
    assert ok[0]
    assert np.linalg.norm(out[0] - [45.0, 43.0]) < 0.3


def test_young_tracks_and_far_results_keep_the_chained_position():
    cfg = FeatureConfig(klt_birth_anchor_px=1.0, klt_birth_anchor_min_age=2)
    birth8, cur8 = _blobs((0, 0)), _blobs((5.0, 3.0))
    a = BirthAnchors()
    ids = np.array([1, 2], np.int64)
    a.register(ids, np.array([[40.0, 40.0], [100.0, 50.0]], np.float32), birth8)
    pos = np.array([[48.0, 43.0], [108.0, 53.0]], np.float32)
    out, _ = a.anchor(cur8, ids, pos, np.ones(2, bool), cfg)  # one MCI old: under min_age
    assert np.array_equal(out, pos)
    out, ok = a.anchor(cur8, ids, pos, np.ones(2, bool), cfg)  # now old enough, but 3 px is beyond the 1 px radius
    assert np.array_equal(out, pos) and ok.all()
    out, ok = a.anchor(cur8, ids, pos, np.ones(2, bool), FeatureConfig(klt_birth_anchor_px=1.0, klt_birth_anchor_drop=True,
                                                                        klt_birth_anchor_min_age=2))
    assert not ok.any()


def test_dead_tracks_release_their_birth_images():
    cfg = FeatureConfig(klt_birth_anchor_px=6.0)
    a = BirthAnchors()
    a.register(np.array([1], np.int64), np.array([[40.0, 40.0]], np.float32), _blobs((0, 0)))
    a.anchor(_blobs((1, 0)), np.array([1], np.int64), np.array([[41.0, 40.0]], np.float32), np.array([False]), cfg)
    assert a.births == {} and a.images == {}
