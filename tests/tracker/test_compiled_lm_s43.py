"""The registrations' compiled loops (session 43) equal the Python loops they replace to rounding: the event
registration's Gauss-Newton passes against its Python loop (kept for the per-edge terms), the
field registration's Levenberg-Marquardt loop against the gtsam / numpy loop it was, both with and without a prior."""

import gtsam
import numpy as np
import pytest
from test_event_registration import K, T_REF, TWIST, exact_events, ground_lines, perturbed, registration

from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker import event_registration as er
from evpose.tracker import registration as reg
from evpose.tracker.event_gauss_newton import passes_python
from evpose.tracker.registration_config import RegistrationConfig


@pytest.mark.parametrize("with_prior", [False, True])
def test_compiled_event_passes_equal_the_python_loop_to_rounding(monkeypatch, with_prior):
    cmap = ground_lines()
    prior = (perturbed(), np.diag([4e5] * 3 + [2e3] * 3)) if with_prior else None
    outs = []
    for path in ("compiled", "python"):
        if path == "python":
            monkeypatch.setattr(er, "passes_compiled", passes_python)
        r = registration(cmap)
        out = r.refine(perturbed(), np.arange(len(cmap)), None, *exact_events(cmap), T_REF, TWIST, K, prior)
        assert out is not None and r.last_events > 2000
        outs.append((out, r._last[1].copy(), r._last[2].copy(), r.learn(), r.offsets.copy()))
    (a, sw_a, swr_a, n_a, off_a), (b, sw_b, swr_b, n_b, off_b) = outs
    assert np.abs(gtsam.Pose3(mat=a[0]).logmap(gtsam.Pose3(mat=perturbed()))).max() > 1e-3  # the pose moved
    assert np.abs(gtsam.Pose3(mat=a[0]).logmap(gtsam.Pose3(mat=b[0]))).max() < 1e-13
    assert np.allclose(a[1], b[1], rtol=1e-9, atol=0)
    assert np.allclose(sw_a, sw_b, rtol=1e-9, atol=1e-12) and np.allclose(swr_a, swr_b, rtol=1e-6, atol=1e-12)
    assert n_a == n_b > 0 and np.allclose(off_a, off_b, rtol=1e-6, atol=1e-12)


def _python_lm(pts, slots, fld, pose, K, config, loss, k, thr, prior):
    """The field registration's LM loop as it was before session 43 (gtsam poses, numpy prior terms; no lag floor)."""
    m = pts.shape[0]
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    args = (fld.value, fld.grad_u, fld.grad_v, fld.box, bool(config.second_order), loss, k, thr)
    off = (reg._NO_TANGENTS, reg._NO_TWIST, 0.0, 0.0, reg._NO_EXTRA, False)
    bufs = lambda: [np.zeros((6, 6)), np.zeros(6), np.empty(m), np.empty(m), np.empty((m, 2))]  # noqa: E731
    cur, trial = bufs(), bufs()

    def prior_terms(p):
        if prior is None:
            return 0.0, None
        e = prior[0].logmap(p)
        return 0.5 * float(e @ prior[1] @ e), prior[1] @ e

    cost, inside, *_ = reg._linearise_at(pts, slots, pose.inverse().matrix(), fx, fy, cx, cy, *args, *cur, *off)
    pc, pg = prior_terms(pose)
    lam, it = float(config.lm_lambda), 0
    for it in range(1, int(config.max_iterations) + 1):
        delta, finite = reg._lm_step(cur[0], cur[1], *((prior[1], pg) if prior else reg._NO_PRIOR_TERMS), prior is not None, lam)
        if not finite:
            break
        cand = pose.compose(gtsam.Pose3.Expmap(delta))
        c_cost, c_inside, *_ = reg._linearise_at(pts, slots, cand.inverse().matrix(), fx, fy, cx, cy, *args, *trial, *off)
        c_pc, c_pg = prior_terms(cand)
        old_mean, new_mean = (cost + pc) / max(inside, 1), (c_cost + c_pc) / c_inside
        if new_mean <= old_mean:
            pose, cost, inside, pc, pg, cur, trial = cand, c_cost, c_inside, c_pc, c_pg, trial, cur
            lam = max(lam * 0.3, float(config.lm_lambda_min))
            small = np.linalg.norm(delta[:3]) < config.convergence_rotation_rad and np.linalg.norm(delta[3:]) < config.convergence_translation_m
            if small or old_mean - new_mean < config.convergence_cost_ratio * old_mean:
                break
        else:
            lam = lam * 10.0 if lam > 0 else 1e-4
    return pose, cost, inside, it, cur[2]


@pytest.mark.parametrize("with_prior", [False, True])
def test_compiled_field_lm_loop_equals_the_python_loop_to_rounding(with_prior):
    rng = np.random.default_rng(4)
    w, h, f = 160, 120, 100.0
    Kf = np.array([[f, 0, 80.0], [0, f, 60.0], [0, 0, 1.0]])
    pts = np.c_[rng.uniform(-1.5, 1.5, (400, 2)), rng.uniform(2, 4, 400)]
    # A field low along the true points' projections: a smooth bowl per point, so the loop has a minimum to walk to.
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    val = np.ones((h, w))
    for X, Y, Z in pts:
        val = np.minimum(val, np.hypot(uu - (f * X / Z + 80.0), vv - (f * Y / Z + 60.0)) / 6.0)
    fld = TemporalDistanceField(DistanceFieldConfig(), w, h)
    fld.value[0] = val.astype(np.float32)
    fld.grad_v[0], fld.grad_u[0] = (g.astype(np.float32) for g in np.gradient(val))
    fld.box[:] = (0, h, 0, w)
    config = RegistrationConfig(max_iterations=8, convergence_cost_ratio=0.0)
    slots = np.zeros(400, np.int8)
    start = gtsam.Pose3.Expmap(np.array([0.01, -0.008, 0.012, 0.03, -0.02, 0.04]))
    prior = (gtsam.Pose3.Expmap(np.array([0.002, 0.0, 0.0, 0.0, 0.01, 0.0])), np.diag([3e3] * 3 + [40.0] * 3)) if with_prior else None
    new = reg._levenberg_marquardt(pts, slots, fld, start, Kf, config, 1, 0.3, 0.5, prior)
    old = _python_lm(pts, slots, fld, start, Kf, config, 1, 0.3, 0.5, prior)
    assert new[9] == old[3] >= 3 and new[2] == old[2]
    assert np.abs(start.logmap(new[0])).max() > 1e-2  # it moved
    assert np.abs(new[0].logmap(old[0])).max() < 1e-13
    assert abs(new[1] - old[1]) <= 1e-10 * abs(old[1]) and np.allclose(new[6], old[4], rtol=1e-9, atol=1e-12)


def _spd(rng, scale):
    M = rng.normal(size=(6, 6))
    return (M @ M.T + 0.1 * np.eye(6)) * scale


def test_compiled_pose_combination_equals_the_gtsam_recipe_to_rounding():
    from evpose.tracker.pose_combination import _combine_python, combine_poses

    rng = np.random.default_rng(6)
    for _ in range(50):
        T_f = gtsam.Pose3.Expmap(rng.normal(size=6)).matrix()
        T_e = (gtsam.Pose3(mat=T_f) * gtsam.Pose3.Expmap(rng.normal(size=6) * 2e-3)).matrix()
        cov_f, cov_e = _spd(rng, 1e-6), _spd(rng, 1e-6)
        for convex in (False, True):
            T, P = combine_poses(T_f, cov_f, T_e, cov_e, convex)
            T_ref, P_ref = _combine_python(T_f, cov_f, T_e, cov_e, convex)
            assert np.abs(T - T_ref).max() < 1e-14 and np.array_equal(T[3], [0, 0, 0, 1])
            assert np.allclose(P, P_ref, rtol=1e-9, atol=0) and np.array_equal(P, P.T)


def test_a_singular_field_covariance_still_raises_and_an_indefinite_events_one_is_not_combined_by_cholesky():
    from evpose.tracker.pose_combination import _combine_kernel, combine_poses

    rng = np.random.default_rng(7)
    T = np.eye(4)
    with pytest.raises(np.linalg.LinAlgError):
        combine_poses(T, np.zeros((6, 6)), T, _spd(rng, 1.0))
    indefinite = _spd(rng, 1.0) - 50.0 * np.eye(6)
    assert not _combine_kernel(T, _spd(rng, 1.0), T, indefinite, False, np.empty((4, 4)), np.empty((6, 6)))


def test_spd_inverse_equals_lapack_to_rounding_and_rejects_what_is_not_positive_definite():
    from evpose.core.spd_kernels import spd_inverse

    rng = np.random.default_rng(8)
    out = np.empty((6, 6))
    for _ in range(50):
        A = _spd(rng, 10.0 ** rng.uniform(-6, 6))
        assert spd_inverse(A, out) and np.allclose(out, np.linalg.inv(A), rtol=1e-8, atol=0) and np.array_equal(out, out.T)
    assert not spd_inverse(-np.eye(6), out)
    assert not spd_inverse(np.diag([1.0, 1, 1, 1, 1, 0]), out)
    assert not spd_inverse(np.full((6, 6), np.nan), out)


def test_jacobi_eigenvalues_equal_lapack_on_normalised_normal_matrices():
    from evpose.core.spd_kernels import sym_eigenvalues

    rng = np.random.default_rng(9)
    w = np.empty(6)
    for _ in range(200):
        Q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
        A = Q @ np.diag(10.0 ** rng.uniform(-8, 0, 6)) @ Q.T
        d = np.sqrt(A.diagonal())
        A = A / (d[:, None] * d[None, :])
        sym_eigenvalues(A, w)
        ref = np.linalg.eigvalsh(A)
        assert np.abs(w - ref).max() < 1e-14 * ref[-1] and np.all(np.diff(w) >= 0)


def test_field_health_and_covariance_match_the_lapack_recipe_and_report_each_failure():
    from evpose.tracker import field_lm_kernel as fk

    rng = np.random.default_rng(10)
    H, info = _spd(rng, 1e4), np.diag([1e3] * 6)
    ad = gtsam.Pose3.Expmap(rng.normal(size=6) * 1e-2).AdjointMap()
    cov = np.empty((6, 6))
    for without_prior in (False, True):
        assert fk.health_and_covariance(H + info, 1e8, 0.3, without_prior, info, ad, cov) == fk.OK
        ref = ad @ (np.linalg.inv(H if without_prior else H + info) * 0.3) @ ad.T
        assert np.allclose(cov, ref, rtol=1e-9, atol=0) and np.array_equal(cov, cov.T)
    assert fk.health_and_covariance(np.full((6, 6), np.nan), 1e8, 0.3, False, info, ad, cov) == fk.NON_FINITE
    flat = np.eye(6)
    flat[0, 3] = flat[3, 0] = 1.0 - 1e-10  # two directions nearly alike: condition ~2e10 (the scale alone does not count)
    assert fk.health_and_covariance(flat, 1e8, 0.3, False, info, ad, cov) == fk.DEGENERATE
    assert fk.health_and_covariance(flat, 1e12, 0.3, False, info, ad, cov) == fk.OK
    assert fk.health_and_covariance(H, 1e8, 0.0, False, info, ad, cov) == fk.NO_WEIGHT
    assert fk.health_and_covariance(H, 1e8, 0.3, True, H + np.eye(6), ad, cov) == fk.NO_COVARIANCE
