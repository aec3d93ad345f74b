"""Registration: converges from perturbed poses, exact Jacobian, explicit failure, covariance."""

import gtsam
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from tracker_synthetic import generate

from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.frontend.noise_filter import ConsistencyNoiseFilter, NoiseFilterConfig
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig
from evpose.tracker import registration as reg
from evpose.tracker.registration import RegistrationConfig, register_to_map
from evpose.tracker.visible_map import VisibleMapConfig, visible_points


COARSE_BLUR = 21


@pytest.fixture(scope="module")
def scene():
    rec, cmap, _ = generate(duration_s=0.25, seed=3)
    cal = rec.calibration
    t_query = 200_000
    ev = rec.events.time_window(0, t_query)
    nf = ConsistencyNoiseFilter(NoiseFilterConfig(), cal.width, cal.height)
    ts = SeparatedTimeSurface(TimeSurfaceConfig(), cal.width, cal.height, cal)
    ts.update(ev, nf.filter(ev))
    field = TemporalDistanceField(DistanceFieldConfig(), cal.width, cal.height)
    field.compute(ts, t_query)
    coarse = TemporalDistanceField(DistanceFieldConfig(blur_px=COARSE_BLUR), cal.width, cal.height)
    coarse.compute(ts, t_query)
    T_gt = rec.ground_truth.interpolate(t_query).matrix(0)
    pts = cmap.points[visible_points(cmap.points, T_gt, cal.K, cal.width, cal.height, VisibleMapConfig())]
    return field, pts, T_gt, cal, coarse


def pose_error(A, B):
    dt = np.linalg.norm(A[:3, 3] - B[:3, 3])
    da = np.degrees(Rotation.from_matrix(A[:3, :3].T @ B[:3, :3]).magnitude())
    return dt, da


@pytest.mark.parametrize("seed", range(6))
def test_registration_converges_from_3cm_2deg_perturbations(scene, seed):
    field, pts, T_gt, cal, coarse = scene
    rng = np.random.default_rng(seed)
    rot = rng.normal(size=3)
    trans = rng.normal(size=3)
    xi = np.concatenate([np.radians(2.0) * rot / np.linalg.norm(rot), 0.03 * trans / np.linalg.norm(trans)])
    T0 = (gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(xi)).matrix()
    res = register_to_map([coarse, field], pts, T0, cal.K, RegistrationConfig(max_iterations=40, prior_translation_m=0.0, prior_rotation_deg=0.0))
    assert res.success, res.reason
    dt, da = pose_error(res.T_world_cam, T_gt)
    assert dt < 0.012 and da < 0.4, (dt, da)


def test_registration_jacobian_matches_finite_differences_on_a_smooth_field(scene):
    field, pts, T_gt, cal, coarse = scene
    f = TemporalDistanceField(DistanceFieldConfig(), cal.width, cal.height)
    vv, uu = np.mgrid[0 : cal.height, 0 : cal.width].astype(np.float64)
    # A bilinear field is represented exactly by bilinear interpolation, value and gradient alike.
    f.value[0] = 0.01 * uu - 0.02 * vv + 1e-4 * uu * vv
    f.grad_u[0] = 0.01 + 1e-4 * vv
    f.grad_v[0] = -0.02 + 1e-4 * uu
    f.box[:] = (0, cal.height, 0, cal.width)
    P = np.ascontiguousarray(pts)
    m = P.shape[0]
    slots = np.zeros(m, np.int8)

    def lin(T):
        Tcw = np.linalg.inv(T)
        H, b = np.zeros((6, 6)), np.zeros(6)
        out = reg._linearise(P, slots, np.ascontiguousarray(Tcw[:3, :3]), np.ascontiguousarray(Tcw[:3, 3]), cal.fx, cal.fy, cal.cx, cal.cy,
                             f.value, f.grad_u, f.grad_v, f.box, False, 0, 1.0, 1.0, H, b, np.empty(m), np.empty(m), np.empty((m, 2)),
                             reg._NO_TANGENTS, reg._NO_TWIST, 0.0, 0.0, reg._NO_EXTRA, False)
        return out[0], b

    _, b = lin(T_gt)
    eps = 1e-5
    for k in range(6):
        d = np.zeros(6)
        d[k] = eps
        cp, _ = lin((gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(d)).matrix())
        cm, _ = lin((gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(-d)).matrix())
        assert np.isclose((cp - cm) / (2 * eps), b[k], rtol=1e-4, atol=1e-3)


def test_registration_reports_a_covariance_at_success(scene):
    field, pts, T_gt, cal, coarse = scene
    res = register_to_map(field, pts, T_gt, cal.K, RegistrationConfig())
    assert res.success
    assert res.covariance.shape == (6, 6)
    assert np.all(np.linalg.eigvalsh(res.covariance) > 0)
    assert res.residuals.shape == (pts.shape[0],) and res.uv.shape == (pts.shape[0], 2)


def test_registration_without_events_fails_with_a_reason(scene):
    _, pts, T_gt, cal, _ = scene
    empty = TemporalDistanceField(DistanceFieldConfig(), cal.width, cal.height)
    empty.compute(SeparatedTimeSurface(TimeSurfaceConfig(), cal.width, cal.height), 200_000)
    res = register_to_map(empty, pts, T_gt, cal.K, RegistrationConfig())
    assert not res.success and "recent events" in res.reason


def test_registration_whose_residuals_all_lie_beyond_tukeys_scale_fails_with_a_reason(scene):
    # The prior alone then made H, and the covariance was 0: the fused modes raised "Singular matrix" on inverting it.
    field, pts, T_gt, cal, coarse = scene
    res = register_to_map(field, pts, T_gt, cal.K, RegistrationConfig(robust_loss="tukey", robust_scale=0.05))
    assert not res.success and res.covariance is None and "all weights 0" in res.reason


def test_registration_with_the_map_out_of_view_fails(scene):
    field, pts, T_gt, cal, coarse = scene
    res = register_to_map(field, pts + np.array([0.0, 0.0, 50.0]), T_gt, cal.K, RegistrationConfig())
    assert not res.success and "project into the image" in res.reason


def test_subsampling_is_deterministic_and_evenly_spread():
    idx = reg.subsample_indices(10_000, 1500)
    assert idx.size == 1500 and np.array_equal(idx, reg.subsample_indices(10_000, 1500))
    assert idx[0] == 0 and idx[-1] > 9_990 and np.all(np.diff(idx) > 0)
    assert np.array_equal(reg.subsample_indices(10, 1500), np.arange(10))


def _twist_at(rec, t_us, dt_us=1000):
    """Body-frame ground-truth velocity (rotation rad/s, translation m/s) over the ``dt_us`` before ``t_us``."""
    T0 = gtsam.Pose3(rec.ground_truth.interpolate(t_us - dt_us).matrix(0))
    T1 = gtsam.Pose3(rec.ground_truth.interpolate(t_us).matrix(0))
    return np.asarray(gtsam.Pose3.Logmap(T0.between(T1))) / (dt_us * 1e-6)


def test_motion_twist_registers_at_the_lagged_time_and_returns_the_query_time_pose(scene):
    field, pts, T_gt, cal, coarse = scene
    xi = np.array([0.2, -0.1, 0.05, 1.5, -0.5, 0.8])
    cfg = RegistrationConfig(field_lag_ms=4.0)
    lag = gtsam.Pose3.Expmap(xi * 4e-3)
    res = register_to_map(field, pts, T_gt, cal.K, cfg, twist_per_s=xi)
    back = (gtsam.Pose3(T_gt) * lag.inverse()).matrix()
    ref = register_to_map(field, pts, back, cal.K, cfg)
    assert np.allclose(res.T_world_cam, (gtsam.Pose3(ref.T_world_cam) * lag).matrix(), atol=1e-12)
    assert np.array_equal(res.residuals, ref.residuals) and res.success == ref.success
    # No lag configured: the twist changes nothing.
    none = RegistrationConfig(field_lag_ms=0.0)
    a = register_to_map(field, pts, T_gt, cal.K, none, twist_per_s=xi)
    b = register_to_map(field, pts, T_gt, cal.K, none)
    assert np.array_equal(a.T_world_cam, b.T_world_cam)


def test_lag_compensation_moves_the_pose_towards_ground_truth_on_a_moving_scene(scene):
    field, pts, T_gt, cal, coarse = scene
    rec, _, _ = generate(duration_s=0.25, seed=3)
    xi = _twist_at(rec, 200_000)
    cfg = RegistrationConfig(prior_translation_m=0.0)
    plain = register_to_map(field, pts, T_gt, cal.K, cfg)
    comp = register_to_map(field, pts, T_gt, cal.K, cfg, twist_per_s=xi)
    assert plain.success and comp.success
    e_plain, _ = pose_error(plain.T_world_cam, T_gt)
    e_comp, _ = pose_error(comp.T_world_cam, T_gt)
    assert e_comp < e_plain - 5e-4, (e_comp, e_plain)


def test_zero_prior_information_means_no_prior(scene):
    field, pts, T_gt, cal, coarse = scene
    T0 = (gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(np.array([0.01, 0, 0, 0.01, 0, 0]))).matrix()
    a = register_to_map(field, pts, T0, cal.K, RegistrationConfig(), prior_information=np.zeros((6, 6)))
    b = register_to_map(field, pts, T0, cal.K, RegistrationConfig(prior_translation_m=0.0, prior_rotation_deg=0.0))
    assert np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.covariance, b.covariance)


def test_a_strong_prior_information_holds_the_pose_and_the_covariance_is_the_events_alone(scene):
    field, pts, T_gt, cal, coarse = scene
    T0 = (gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(np.array([0.0, 0.005, 0, 0.01, 0.0, 0]))).matrix()
    strong = register_to_map(field, pts, T0, cal.K, RegistrationConfig(), prior_information=np.eye(6) * 1e12)
    assert strong.success
    assert pose_error(strong.T_world_cam, T0)[0] < 1e-5
    # The reported covariance carries the events' information only, not the (huge) prior's: near the optimum
    # it is about what a registration without a prior reports.
    free = register_to_map(field, pts, T_gt, cal.K, RegistrationConfig(prior_translation_m=0.0, prior_rotation_deg=0.0))
    strong = register_to_map(field, pts, free.T_world_cam, cal.K, RegistrationConfig(), prior_information=np.eye(6) * 1e12)
    assert strong.covariance is not None
    ratio = np.diag(strong.covariance) / np.diag(free.covariance)
    assert np.all(ratio > 0.2) and np.all(ratio < 5.0), ratio


def test_inlier_residual_variance_gives_a_smaller_covariance_of_the_same_shape(scene):
    field, pts, T_gt, cal, coarse = scene
    cfg = RegistrationConfig(prior_translation_m=0.0, prior_rotation_deg=0.0)
    everyone = register_to_map(field, pts, T_gt, cal.K, cfg)
    cfg.residual_variance = reg.ResidualVariance.INLIERS
    inliers = register_to_map(field, pts, T_gt, cal.K, cfg)
    assert np.array_equal(everyone.T_world_cam, inliers.T_world_cam)  # only the covariance's scale changes
    assert np.any(everyone.residuals > cfg.inlier_threshold)  # points that did not fire count only in "all"
    ratio = inliers.covariance / everyone.covariance
    assert np.allclose(ratio, ratio[0, 0]) and 0.0 < ratio[0, 0] < 1.0


def test_prior_residual_sigma_argument_scales_the_prior_information(scene):
    field, pts, T_gt, cal, coarse = scene
    T0 = (gtsam.Pose3(T_gt) * gtsam.Pose3.Expmap(np.array([0.0, 0.01, 0, 0.02, 0.0, 0]))).matrix()
    info = np.eye(6) * 1e4
    cfg = RegistrationConfig(prior_residual_sigma=0.2)
    same = register_to_map(field, pts, T0, cal.K, cfg, prior_information=info, prior_residual_sigma=0.2)
    default = register_to_map(field, pts, T0, cal.K, cfg, prior_information=info)
    assert np.array_equal(same.T_world_cam, default.T_world_cam)
    # A larger sigma makes the same information a stiffer prior: the pose stays nearer its start.
    loose = register_to_map(field, pts, T0, cal.K, cfg, prior_information=info, prior_residual_sigma=0.05)
    stiff = register_to_map(field, pts, T0, cal.K, cfg, prior_information=info, prior_residual_sigma=2.0)
    assert pose_error(stiff.T_world_cam, T0)[0] < pose_error(loose.T_world_cam, T0)[0]


def test_damped_step_solves_the_levenberg_marquardt_system():
    rng = np.random.default_rng(0)
    M = rng.normal(size=(6, 6))
    H = M @ M.T + 0.1 * np.eye(6)
    b = rng.normal(size=6)
    lam = 0.3
    expected = -np.linalg.solve(H + lam * np.diag(np.diag(H) + 1e-12), b)
    assert np.allclose(reg._damped_step(H, b, lam), expected, rtol=1e-10, atol=1e-12)
    assert np.all(np.isnan(reg._damped_step(np.zeros((6, 6)), b, 0.0)))


def _line_field(cal, min_col):
    """A field reading |column - min_col| / 4 (a vertical valley), exactly bilinear, over the whole image."""
    f = TemporalDistanceField(DistanceFieldConfig(), cal.width, cal.height)
    uu = np.broadcast_to(np.arange(cal.width, dtype=np.float64)[None, :], (cal.height, cal.width))
    f.value[0] = np.abs(uu - min_col) / 4.0
    f.grad_u[0] = np.sign(uu - min_col) / 4.0
    f.grad_v[0] = 0.0
    f.box[:] = (0, cal.height, 0, cal.width)
    return f


@pytest.mark.parametrize("lag_s, floor_px", [(0.0, 0.5), (0.004, 0.7)])
def test_lag_floor_samples_each_point_behind_its_projection_against_its_image_motion(scene, lag_s, floor_px):
    _, _, _, cal, _ = scene
    expected_shift_px = 0.5  # floor less the lag's share (lag x 50 px/s); cx + 0.5 is a whole pixel, where |u - m| is exact
    assert (cal.cx + expected_shift_px) % 1.0 == 0.0
    # A vertical edge at X = 0, 2 m ahead; the camera moves along +x, so the edge moves towards -u at 0.05 px/ms:
    # its field's minimum trails it on the +u side.
    ys = np.linspace(-0.2, 0.2, 9)
    P = np.ascontiguousarray(np.c_[np.zeros_like(ys), ys, np.full_like(ys, 2.0)])
    tangents = np.ascontiguousarray(np.tile([0.0, 1.0, 0.0], (ys.size, 1)))
    speed_px_s = 50.0
    twist = np.array([0.0, 0.0, 0.0, speed_px_s * 2.0 / cal.fx, 0.0, 0.0])
    m = P.shape[0]

    def residuals(field, floor_px):
        H, b, res = np.zeros((6, 6)), np.zeros(6), np.empty(m)
        reg._linearise(P, np.zeros(m, np.int8), np.eye(3), np.zeros(3), cal.fx, cal.fy, cal.cx, cal.cy, field.value, field.grad_u,
                       field.grad_v, field.box, False, 0, 1.0, 1.0, H, b, res, np.empty(m), np.empty((m, 2)), tangents, twist, lag_s,
                       floor_px, reg._NO_EXTRA, False)
        return res

    # The point reads the field that far behind its projection, where the minimum is.
    field = _line_field(cal, cal.cx + expected_shift_px)
    assert np.allclose(residuals(field, floor_px), 0.0, atol=1e-9)
    assert np.allclose(residuals(field, 0.0), expected_shift_px / 4.0, atol=1e-9)  # off: read at the projection
    # The edge moving the other way puts the trail on the other side.
    twist[3] = -twist[3]
    assert np.allclose(residuals(_line_field(cal, cal.cx - expected_shift_px), floor_px), 0.0, atol=1e-9)


def test_lag_floor_is_off_without_tangents_or_twist(scene):
    field, pts, T_gt, cal, _ = scene
    cfg = RegistrationConfig(lag_floor_px=0.5)
    base = register_to_map(field, pts, T_gt, cal.K, RegistrationConfig())
    no_tangents = register_to_map(field, pts, T_gt, cal.K, cfg, twist_per_s=None, tangents_world=np.tile([1.0, 0.0, 0.0], (len(pts), 1)))
    no_twist = register_to_map(field, pts, T_gt, cal.K, cfg)
    assert np.array_equal(base.T_world_cam, no_twist.T_world_cam) and np.array_equal(base.T_world_cam, no_tangents.T_world_cam)


def test_trail_offsets_move_each_point_behind_or_ahead_of_the_lag_model(scene):
    _, _, _, cal, _ = scene
    ys = np.linspace(-0.2, 0.2, 5)
    P = np.ascontiguousarray(np.c_[np.zeros_like(ys), ys, np.full_like(ys, 2.0)])
    tangents = np.ascontiguousarray(np.tile([0.0, 1.0, 0.0], (ys.size, 1)))
    twist = np.array([0.0, 0.0, 0.0, 50.0 * 2.0 / cal.fx, 0.0, 0.0])  # the edge moves towards -u
    m = P.shape[0]

    def residuals(field, extra):
        res = np.empty(m)
        reg._linearise(P, np.zeros(m, np.int8), np.eye(3), np.zeros(3), cal.fx, cal.fy, cal.cx, cal.cy, field.value, field.grad_u,
                       field.grad_v, field.box, False, 0, 1.0, 1.0, np.zeros((6, 6)), np.zeros(6), res, np.empty(m), np.empty((m, 2)),
                       tangents, twist, 0.0, 0.0, np.full(m, extra), False)
        return res

    assert np.allclose(residuals(_line_field(cal, cal.cx + 0.5), 0.5), 0.0, atol=1e-9)  # behind: +u
    assert np.allclose(residuals(_line_field(cal, cal.cx - 0.5), -0.5), 0.0, atol=1e-9)  # negative: ahead


@pytest.mark.parametrize("second_order", [False, True])
def test_normal_only_ignores_the_field_gradient_along_each_points_edge(scene, second_order):
    _, _, _, cal, _ = scene
    ys = np.linspace(-0.2, 0.2, 7)
    P = np.ascontiguousarray(np.c_[np.full_like(ys, 0.01), ys, np.full_like(ys, 2.0)])
    tangents = np.ascontiguousarray(np.tile([0.0, 1.0, 0.0], (ys.size, 1)))  # vertical edges: normal along u
    m = P.shape[0]

    def normal_equations(field, normal_only):
        H, b = np.zeros((6, 6)), np.zeros(6)
        reg._linearise(P, np.zeros(m, np.int8), np.eye(3), np.zeros(3), cal.fx, cal.fy, cal.cx, cal.cy, field.value, field.grad_u,
                       field.grad_v, field.box, second_order, 0, 1.0, 1.0, H, b, np.empty(m), np.empty(m), np.empty((m, 2)),
                       tangents, reg._NO_TWIST, 0.0, 0.0, reg._NO_EXTRA, normal_only)
        return H, b

    clean = _line_field(cal, cal.cx - 1.0)
    scattered = _line_field(cal, cal.cx - 1.0)
    scattered.grad_v[0] = 0.05  # a gradient along the edge (the events' scatter), which normal-only must not see
    H0, b0 = normal_equations(clean, False)
    H1, b1 = normal_equations(scattered, True)
    H2, b2 = normal_equations(scattered, False)
    assert np.allclose(H1, H0, atol=1e-12) and np.allclose(b1, b0, atol=1e-12)
    assert not np.allclose(b2, b0, atol=1e-6)
