"""Session 42 (drift42): the birth patch's structure tensor (edge direction, eigenvalue ratio), the edge-slide check
ending tracks that slide along their birth edge against their neighbours, the weak-dot gate at detection, and KLT's
minimum-eigenvalue threshold."""

import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.edge_slide import EdgeSlide, edge_directions, tensor_ratio
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.features import detect_features, track_features
from tests.slam.test_features import _corners_and_noise


def _step_image() -> np.ndarray:
    img = np.zeros((90, 120), np.uint8)
    img[:, 60:] = 200  # a vertical edge at x = 60
    img[60:, :20] = 150  # a block whose corner is at (20, 60)
    return img


def test_edge_direction_runs_along_a_straight_edge_and_the_ratio_separates_edge_corner_and_flat():
    img = _step_image()
    d = edge_directions(img, np.array([[60.0, 20.0]]), 23)[0]
    assert abs(abs(d[1]) - 1.0) < 1e-6 and abs(d[0]) < 1e-6
    r = tensor_ratio(img, np.array([[60.0, 20.0], [20.0, 60.0], [100.0, 20.0]]), 23)
    assert r[0] < 0.01  # straight edge
    assert r[1] > 0.5  # a right-angle corner is near isotropic over the window
    assert r[2] == 1.0  # flat: no gradient at all


def test_edge_slide_ends_only_the_track_that_slides_along_its_birth_edge():
    img = _step_image()
    cfg = FeatureConfig(klt_edge_slide_px=2.0, klt_edge_slide_neighbours=4)
    rng = np.random.default_rng(0)
    uv = np.c_[rng.uniform(10, 110, 12), rng.uniform(10, 80, 12)]
    uv[0] = (60.0, 40.0)  # on the vertical edge
    ids = np.arange(12)
    es = EdgeSlide()
    pos = uv.copy()
    common = np.array([0.5, 0.0])  # the scene's image motion: across the edge
    alive = np.ones(12, bool)
    for _ in range(6):
        new = pos + common
        new[0] += (0.0, 0.8)  # track 0 also slides down its edge
        ok = es.check(img, ids, pos, new, np.ones(12, bool), cfg)
        alive &= ok
        pos = new
    assert not alive[0]
    assert alive[1:].all()
    assert set(es.state) == set(ids[alive].tolist())


def test_edge_slide_ignores_motion_across_the_edge_shared_with_the_neighbours():
    img = _step_image()
    cfg = FeatureConfig(klt_edge_slide_px=1.0, klt_edge_slide_neighbours=3)
    uv = np.array([[60.0, 20.0], [60.0, 40.0], [60.0, 60.0], [60.0, 80.0], [30.0, 20.0]])
    es = EdgeSlide()
    ok = es.check(img, np.arange(5), uv, uv + (3.0, 0.0), np.ones(5, bool), cfg)
    assert ok.all()


def test_weak_dot_gate_drops_isolated_dots_and_keeps_the_corners():
    x, y = _corners_and_noise()
    img8 = to_uint8(event_image(x, y, None, 240, 180, 1.0))
    cfg = FeatureConfig()
    plain = detect_features(img8, cfg)
    cfg.blob_max_quality = 0.05
    gated = detect_features(img8, cfg)
    near_corner = lambda p: min(np.hypot(p[0] - cx, p[1] - cy) for cx, cy in ((50, 40), (150, 40), (50, 120), (150, 120))) < 4
    assert sum(not near_corner(p) for p in gated) < sum(not near_corner(p) for p in plain)
    assert sum(near_corner(p) for p in gated) == sum(near_corner(p) for p in plain) >= 4


def test_klt_min_eig_raised_loses_the_track_on_a_flat_patch_and_keeps_the_corner():
    img = np.zeros((90, 120), np.uint8)
    img[30:60, 40:80] = 200
    pts = np.array([[40.0, 30.0], [100.0, 75.0]], np.float32)  # a corner of the block, a flat patch
    cfg = FeatureConfig()
    _, ok = track_features(img, img, pts, cfg)
    assert ok[0]
    cfg.klt_min_eig = 0.05
    _, ok_hi = track_features(img, img, pts, cfg)
    assert ok_hi[0] and not ok_hi[1]


def test_edge_follow_gives_an_edge_track_its_neighbours_step_along_the_edge_and_keeps_its_own_across():
    img = _step_image()
    cfg = FeatureConfig(klt_edge_follow_max_ratio=0.1, klt_edge_slide_neighbours=3)
    uv = np.array([[60.0, 40.0], [30.0, 20.0], [90.0, 20.0], [30.0, 80.0], [90.0, 80.0]])
    new = uv + (0.5, 0.2)  # the scene's step
    new[0] = uv[0] + (0.7, 1.5)  # the edge track: across the edge a little more, along it far more
    out = EdgeSlide().follow(img, np.arange(5), uv, new, np.ones(5, bool), cfg)
    assert np.allclose(out[0], uv[0] + (0.7, 0.2))  # along the (vertical) edge: the neighbours' 0.2; across: its own 0.7
    assert np.allclose(out[1:], new[1:])  # the flat-patch tracks (ratio 1) keep their steps


def test_edge_slide_renew_carries_the_slid_track_on_under_a_new_id_without_its_map_point():
    from evpose.slam.features import FrontendTracks

    img = _step_image()
    cfg = FeatureConfig(klt_edge_slide_px=1.0, klt_edge_slide_neighbours=3, klt_edge_slide_renew=True)
    uv = np.array([[60.0, 40.0], [30.0, 20.0], [90.0, 20.0], [30.0, 80.0], [90.0, 80.0]], np.float32)
    fe = FrontendTracks(ids=np.arange(5, dtype=np.int64), uv=uv, prev8=img, next_id=5, track_to_point={0: 7})
    new = uv + np.float32(0.5)
    new[0, 1] += 2.0  # track 0 slides 2 px down its edge in one step
    ok = fe.slide.step(fe, new, np.ones(5, bool), cfg)
    assert ok.all()
    assert fe.ids.tolist() == [5, 1, 2, 3, 4] and fe.next_id == 6
    assert 5 not in fe.track_to_point
    cfg.klt_edge_slide_renew = False
    fe2 = FrontendTracks(ids=np.arange(5, dtype=np.int64), uv=uv, prev8=img, next_id=5)
    assert fe2.slide.step(fe2, new, np.ones(5, bool), cfg).tolist() == [False, True, True, True, True]
