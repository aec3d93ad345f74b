"""Registration's compiled helpers give the same bits as the numpy / gtsam sequence they replace in the LM loop."""

import gtsam
import numpy as np

from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker import registration as reg


def _spd(rng):
    M = rng.normal(size=(6, 6))
    return M @ M.T + 0.1 * np.eye(6)


def test_lm_step_adds_the_prior_and_solves_bit_for_bit_as_numpy_then_damped_step():
    rng = np.random.default_rng(1)
    for _ in range(50):
        H, P, b, g = _spd(rng), _spd(rng), rng.normal(size=6), rng.normal(size=6)
        lam = float(rng.uniform(1e-4, 10))
        step, finite = reg._lm_step(H, b, P, g, True, lam)
        assert finite and np.array_equal(step, reg._damped_step(H + P, b + g, lam))
        step, finite = reg._lm_step(H, b, P, g, False, lam)
        assert finite and np.array_equal(step, reg._damped_step(H, b, lam))


def test_lm_step_reports_a_singular_or_overflowing_system_as_not_finite():
    b = np.ones(6)
    assert not reg._lm_step(np.zeros((6, 6)), b, np.zeros((6, 6)), b, False, 0.0)[1]
    H = np.eye(6) * 1e-300
    assert not reg._lm_step(H, b * 1e300, H, b, True, 0.0)[1]


def test_linearise_at_a_gtsam_pose_matrix_equals_linearise_with_contiguous_rotation_and_translation():
    rng = np.random.default_rng(2)
    w, h = 120, 90
    f = TemporalDistanceField(DistanceFieldConfig(), w, h)
    f.value[0] = rng.uniform(0, 1, (h, w)).astype(np.float32)
    f.grad_u[0] = rng.normal(size=(h, w)).astype(np.float32)
    f.grad_v[0] = rng.normal(size=(h, w)).astype(np.float32)
    f.box[:] = (0, h, 0, w)
    pts = np.c_[rng.uniform(-1, 1, (300, 2)), rng.uniform(2, 4, 300)]
    slots = np.zeros(300, np.int8)
    off = (reg._NO_TANGENTS, reg._NO_TWIST, 0.0, 0.0, reg._NO_EXTRA, False)  # no lag floor, both gradient directions
    T_cw = gtsam.Pose3(gtsam.Rot3.Rodrigues(0.01, -0.02, 0.03), np.array([0.05, -0.02, 0.1])).inverse().matrix()
    for second_order in (False, True):
        a = [np.zeros((6, 6)), np.zeros(6), np.empty(300), np.empty(300), np.empty((300, 2))]
        b = [np.zeros((6, 6)), np.zeros(6), np.empty(300), np.empty(300), np.empty((300, 2))]
        ra = reg._linearise_at(pts, slots, T_cw, 100.0, 100.0, 60.0, 45.0, f.value, f.grad_u, f.grad_v, f.box, second_order,
                               1, 0.3, 0.5, *a, *off)
        rb = reg._linearise(pts, slots, np.ascontiguousarray(T_cw[:3, :3]), np.ascontiguousarray(T_cw[:3, 3]), 100.0, 100.0,
                            60.0, 45.0, f.value, f.grad_u, f.grad_v, f.box, second_order, 1, 0.3, 0.5, *b, *off)
        assert ra == rb
        for x, y in zip(a, b):
            assert np.array_equal(x, y, equal_nan=True)


def test_inv_equals_numpys_bit_for_bit():
    rng = np.random.default_rng(3)
    for _ in range(20):
        H = _spd(rng)
        assert np.array_equal(reg._inv(H), np.linalg.inv(H))
