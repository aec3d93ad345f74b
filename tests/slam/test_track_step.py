"""One MCI-to-MCI KLT step's gate and correction: the first-step gate drops a new track that left the homography of
the older ones, and the removal of the warp's curvature shift moves a turning track out of the turn by the model."""

import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.features import FrontendTracks
from evpose.slam.track_step import remove_curvature_shift, step_consistent


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
