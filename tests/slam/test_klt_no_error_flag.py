"""KLT without OpenCV's final patch-difference pass (``features.KLT_NO_ERROR``) keeps every track and position."""
import cv2
import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.features import track_features
from evpose.slam.keyframe_search import klt_near
from slam_synthetic import shifted_image_pair

W, H = 160, 120


def _pair(rng, shift):
    return shifted_image_pair(rng, shift, W, H)


def _track_features_ref(prev8, cur8, pts, cfg, guess=None, guess_back=False):
    """The session-25 form: OpenCV's error pass on (flags without ``OPTFLOW_LK_GET_MIN_EIGENVALS``)."""
    p0 = np.ascontiguousarray(pts, np.float32).reshape(-1, 1, 2)
    win = (int(cfg.klt_window_px), int(cfg.klt_window_px))
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01)
    flags, p1_init = 0, None
    if guess is not None:
        p1_init = np.ascontiguousarray(guess, np.float32).reshape(-1, 1, 2).copy()
        flags = cv2.OPTFLOW_USE_INITIAL_FLOW
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(prev8, cur8, p0, p1_init, winSize=win, maxLevel=int(cfg.klt_levels), criteria=crit, flags=flags)
    p0_init, flags_b = None, 0
    if guess_back and p1_init is not None:
        p0_init = (p0 + (p1 - p1_init)).astype(np.float32)
        flags_b = cv2.OPTFLOW_USE_INITIAL_FLOW
    p0b, st2, _ = cv2.calcOpticalFlowPyrLK(cur8, prev8, p1, p0_init, winSize=win, maxLevel=int(cfg.klt_levels), criteria=crit, flags=flags_b)
    p1 = p1.reshape(-1, 2)
    fb = np.linalg.norm(p0b.reshape(-1, 2) - p0.reshape(-1, 2), axis=1)
    h, w = cur8.shape
    ok = (st1.ravel() == 1) & (st2.ravel() == 1) & (fb <= cfg.klt_max_bidir_error_px)
    ok &= (p1[:, 0] >= 0) & (p1[:, 0] <= w - 1) & (p1[:, 1] >= 0) & (p1[:, 1] <= h - 1)
    return p1.astype(np.float32), ok


def test_track_features_equals_klt_with_the_error_pass():
    rng = np.random.default_rng(0)
    cfg = FeatureConfig()
    for k in range(12):
        shift = rng.uniform(-8, 8, 2)
        a, b = _pair(rng, shift)
        pts = np.c_[rng.uniform(0, W - 1, 200), rng.uniform(0, H - 1, 200)].astype(np.float32)
        guess = None if k % 2 else pts + shift.astype(np.float32) + rng.normal(0, 2, pts.shape).astype(np.float32)
        new, ok = track_features(a, b, pts, cfg, guess=guess, guess_back=guess is not None and k % 4 == 0)
        ref, ok_ref = _track_features_ref(a, b, pts, cfg, guess=guess, guess_back=guess is not None and k % 4 == 0)
        np.testing.assert_array_equal(new, ref)
        np.testing.assert_array_equal(ok, ok_ref)


def test_klt_near_equals_forward_backward_with_the_error_pass():
    rng = np.random.default_rng(1)
    cfg = FeatureConfig()
    for _ in range(8):
        shift = rng.uniform(-15, 15, 2)
        a, b = _pair(rng, shift)
        src = np.c_[rng.uniform(0, W - 1, 150), rng.uniform(0, H - 1, 150)].astype(np.float32)
        guess = src + shift.astype(np.float32) + rng.normal(0, 3, src.shape).astype(np.float32)
        found, ok = klt_near(a, b, src, guess, 3.0, cfg)
        ref, ok_ref = _track_features_ref(a, b, src, cfg, guess=guess, guess_back=True)
        ok_ref &= np.linalg.norm(ref.astype(np.float64) - guess.astype(np.float64), axis=1) <= 3.0
        np.testing.assert_array_equal(found, ref)
        np.testing.assert_array_equal(ok, ok_ref)
