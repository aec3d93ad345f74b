"""Re-finding map points by KLT from keyframe MCIs: matches near the projection, conflicts, and the symmetric backward pass."""

from dataclasses import replace

import numpy as np

from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.config import FeatureConfig
from evpose.slam.features import track_features
from evpose.slam.keyframe_search import keep_keyframe_image, klt_near, klt_refind_points
from test_projection_search import K, _image, _scene


def _map_with_keyframe_image():
    Xw, T1, T2, uv1, uv2 = _scene()
    m = SlamMap(0)
    kf = Keyframe(0, 0, T1, {})
    m.keyframes = [kf]
    for i, X in enumerate(Xw):
        m.points[i] = MapPoint(i, X.copy(), {0: uv1[i].copy()}, track_id=i)
    keep_keyframe_image(m, kf, _image(uv1, seed=5), window=6)
    return m, T2, uv2


def test_untracked_points_are_re_found_by_klt_from_their_keyframe_mci():
    m, T2, uv2 = _map_with_keyframe_image()
    cur = _image(uv2, seed=6)  # other events, the same corners seen from the new pose
    T_pred = T2.copy()
    T_pred[:3, 3] += [0.01, 0.0, 0.0]  # projections miss the corners by about a pixel
    tracked = {0}
    pids, uv = klt_refind_points(m, cur, K, T_pred, tracked, uv2[[0]], window=6, radius=3.0, fcfg=FeatureConfig())
    assert 0 not in pids
    assert len(pids) >= 0.8 * (len(m.points) - 1)
    assert np.linalg.norm(uv - uv2[pids], axis=1).max() < 0.7
    again = klt_refind_points(m, cur, K, T_pred, tracked, uv2[[0]], window=6, radius=3.0, fcfg=FeatureConfig())
    assert again[0] == pids and np.array_equal(again[1], uv)


def test_points_missing_from_the_current_mci_or_far_from_the_projection_are_not_matched():
    m, T2, uv2 = _map_with_keyframe_image()
    empty = np.zeros_like(m.keyframes[0].image8)
    assert klt_refind_points(m, empty, K, T2, set(), np.zeros((0, 2)), 6, 3.0, FeatureConfig())[0] == []
    # The corners moved 6 px from where the pose puts them: a match that far from the projection is refused.
    cur = _image(uv2 + np.array([6.0, 0.0]), seed=6)
    assert klt_refind_points(m, cur, K, T2, set(), np.zeros((0, 2)), 6, 3.0, FeatureConfig())[0] == []


def test_only_the_local_window_keeps_keyframe_images():
    m = SlamMap(0)
    img = np.zeros((10, 10), np.uint8)
    for k in range(4):
        m.keyframes.append(Keyframe(k, k, np.eye(4), {}))
        keep_keyframe_image(m, m.keyframes[-1], img, window=2)
    assert [kf.image8 is not None for kf in m.keyframes] == [False, False, True, True]


def test_a_guided_backward_pass_checks_matches_beyond_klt_reach():
    c = np.array([[60.0, 50.0], [160.0, 60.0], [100.0, 130.0]])
    shift = np.array([14.0, -9.0])
    a, b = _image(c, seed=1), _image(c + shift, seed=2)
    cfg = replace(FeatureConfig(), klt_levels=0)  # no pyramid: an unguided pass reaches a few pixels only
    guess = (c + shift + 0.8).astype(np.float32)
    _, ok_plain = track_features(a, b, c.astype(np.float32), cfg, guess=guess)
    found, ok = track_features(a, b, c.astype(np.float32), cfg, guess=guess, guess_back=True)
    assert not ok_plain.any()
    assert ok.all() and np.linalg.norm(found - (c + shift), axis=1).max() < 0.7


def test_klt_near_equals_track_features_with_the_radius_test_bit_for_bit():
    Xw, T1, T2, uv1, uv2 = _scene()
    src8, img8 = _image(uv1, seed=5), _image(uv2, seed=5)
    rng = np.random.default_rng(3)
    guess = uv2 + rng.normal(0.0, 2.0, uv2.shape)  # projections a few pixels off, as by an estimated pose
    fcfg = FeatureConfig()
    found, ok = klt_near(src8, img8, uv1.astype(np.float32), guess, 3.0, fcfg)
    ref, ref_ok = track_features(src8, img8, uv1.astype(np.float32), fcfg, guess=guess.astype(np.float32), guess_back=True)
    ref_ok &= np.linalg.norm(ref.astype(np.float64) - guess, axis=1) <= 3.0
    assert ok.any() and not ok.all()
    np.testing.assert_array_equal(ok, ref_ok)
    np.testing.assert_array_equal(found[ok], ref[ref_ok])
