"""Polarity prediction checked against events rendered from brightness (a miniature ESIM over a painted square)."""

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.fusion.polarity import (
    MapPolaritySelector,
    PolarityFilterConfig,
    PolarityPredictor,
    classify_events,
    filter_summary,
    observed_point_polarity,
)
from evpose.fusion.state import FusedState
from evpose.core.contour_map import ContourMap

W, H = 240, 180
K = np.array([[200.0, 0, 119.5], [0, 200.0, 89.5], [0, 0, 1]])
R_DOWN = np.diag([1.0, -1.0, -1.0])  # camera z along world -z


def _brightness(x, y, half=0.5, soft=0.012):
    s = lambda a: 1.0 / (1.0 + np.exp(-a / soft))  # noqa: E731
    return 0.15 + 0.7 * s(half - np.abs(x)) * s(half - np.abs(y))


def _pose(t, p0, R0, v, w):
    T = np.eye(4)
    T[:3, :3] = R0 @ Rotation.from_rotvec(w * t).as_matrix()
    T[:3, 3] = p0 + v * t
    return T


def _render_log(T):
    vs, us = np.mgrid[0:H, 0:W].astype(np.float64)
    d = np.stack([(us - K[0, 2]) / K[0, 0], (vs - K[1, 2]) / K[1, 1], np.ones_like(us)], -1) @ T[:3, :3].T
    lam = -T[2, 3] / d[..., 2]
    hit = T[:3, 3] + lam[..., None] * d
    return np.log(_brightness(hit[..., 0], hit[..., 1]))


def _events(T0, T1, C=0.12):
    dl = _render_log(T1) - _render_log(T0)
    ys, xs = np.nonzero(np.abs(dl) >= C)
    return xs.astype(np.float64), ys.astype(np.float64), np.sign(dl[ys, xs]).astype(np.int8)


class _MovingAlongX:
    """A fused motion source: pose ``T``, moving at 1 m/s along world x, not rotating."""

    def __init__(self, T):
        self.T = T

    def predict(self, t_us):
        return FusedState(t_us, self.T, np.array([1.0, 0.0, 0.0]), np.zeros(3), np.zeros(3), omega_cam=np.zeros(3))


def _square_map(half=0.5, step=0.01, corner_gap=0.04):
    s = np.arange(-half + corner_gap, half - corner_gap + 1e-9, step)
    pts, nrm = [], []
    for axis, sign in ((0, 1), (0, -1), (1, 1), (1, -1)):
        p = np.zeros((s.size, 3))
        p[:, axis] = sign * half
        p[:, 1 - axis] = s
        n = np.zeros((s.size, 3))
        n[:, axis] = sign
        pts.append(p)
        nrm.append(n)
    pts, nrm = np.concatenate(pts), np.concatenate(nrm)
    # Brightness falls outward (bright square on dark ground): gradient = -edge_normal.
    return ContourMap.from_points(pts, edge_normal=nrm, brightness_sign=-np.ones(len(pts), np.int8))


def _project(points, T):
    R_cw = T[:3, :3].T
    X = (points - T[:3, 3]) @ R_cw.T
    return np.stack([K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]], 1)


def _trial(rng, cmap, predictor, use_map_sign=True, dt=0.012):
    p0 = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(1.6, 2.2)])
    R0 = R_DOWN @ Rotation.from_rotvec(rng.normal(0, 0.08, 3)).as_matrix()
    v = rng.normal(0, 1, 3)
    v *= rng.uniform(1.0, 2.5) / np.linalg.norm(v)
    w = rng.normal(0, 1, 3)
    w *= rng.uniform(0.2, 1.0) / np.linalg.norm(w)
    T0, T1, Tm = _pose(-dt / 2, p0, R0, v, w), _pose(dt / 2, p0, R0, v, w), _pose(0.0, p0, R0, v, w)
    x, y, p = _events(T0, T1)
    idx = np.arange(len(cmap))
    sign = cmap.brightness_sign if use_map_sign else np.zeros(len(cmap), np.int8)
    pred = predictor.predict(cmap.points, cmap.edge_normal, sign, Tm, w, v, K, point_index=idx)
    label, point = classify_events(x, y, p, _project(cmap.points, Tm), pred, 2.0, W, H)
    return x, y, p, pred, label, point


def test_polarity_prediction_agrees_with_rendered_events_outside_buffer():
    rng = np.random.default_rng(3)
    cmap = _square_map()
    pred_cfg = PolarityFilterConfig()
    agree = total = 0
    for _ in range(8):
        _, _, p, pred, label, point = _trial(rng, cmap, PolarityPredictor(pred_cfg))
        judged = (point >= 0) & (pred[np.maximum(point, 0)] != 0)
        agree += int(np.count_nonzero(judged & (label == 1)))
        total += int(np.count_nonzero(judged))
    assert total > 2000
    assert agree / total >= 0.9, agree / total


def test_polarity_rule_with_flipped_sign_disagrees_with_rendered_events():
    # The check discriminates: the opposite convention (the paper's '< 90 deg -> ON' read with our gradient) fails.
    rng = np.random.default_rng(3)
    cmap = _square_map()
    flipped = ContourMap.from_points(cmap.points, edge_normal=cmap.edge_normal, brightness_sign=-cmap.brightness_sign)
    agree = total = 0
    for _ in range(3):
        _, _, p, pred, label, point = _trial(rng, flipped, PolarityPredictor())
        judged = (point >= 0) & (pred[np.maximum(point, 0)] != 0)
        agree += int(np.count_nonzero(judged & (label == 1)))
        total += int(np.count_nonzero(judged))
    assert total > 500 and agree / total < 0.1


def test_filter_removes_opposite_polarity_events_and_reports_share():
    rng = np.random.default_rng(5)
    cmap = _square_map()
    _, _, p, pred, label, point = _trial(rng, cmap, PolarityPredictor())
    s = filter_summary(label)
    assert s["events_in_patches"] > 0 and 0.0 <= s["removed_share_of_all"] <= s["removed_share_of_patches"] <= 1.0
    # A removed event is exactly one whose point predicts the other polarity.
    removed = label == 0
    assert np.all(pred[point[removed]] == -p[removed])


def test_unknown_brightness_signs_are_learned_online():
    rng = np.random.default_rng(11)
    cmap = _square_map()
    predictor = PolarityPredictor(PolarityFilterConfig(learn_min_votes=2))
    for k in range(6):
        x, y, p, pred, label, point = _trial(rng, cmap, predictor, use_map_sign=False)
        if k == 0:
            assert np.all(pred == 0)  # nothing learned yet -> both polarities everywhere
        predictor.learn(np.arange(len(cmap)), observed_point_polarity(point, p, len(cmap)))
    learned = predictor.learned_sign(np.arange(len(cmap)))
    known = learned != 0
    assert known.mean() > 0.5
    assert np.mean(learned[known] == cmap.brightness_sign[known]) >= 0.95


def test_buffer_zone_widens_when_image_motion_is_slow():
    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))
    pr = PolarityPredictor()
    fast = pr.predict_full(cmap.points, cmap.edge_normal, cmap.brightness_sign, T, np.zeros(3), np.array([1.0, 0.3, 0.0]), K)
    slow = pr.predict_full(cmap.points, cmap.edge_normal, cmap.brightness_sign, T, np.zeros(3), np.array([0.05, 0.015, 0.0]), K)
    still = pr.predict_full(cmap.points, cmap.edge_normal, cmap.brightness_sign, T, np.zeros(3), np.zeros(3), K)
    assert np.all(slow.buffer_deg > fast.buffer_deg)
    assert np.count_nonzero(slow.polarity) < np.count_nonzero(fast.polarity)
    assert np.all(still.polarity == 0)
    # Pure x motion over a square: the x-facing edges are predicted, the y-facing ones (parallel motion) are not.
    assert np.count_nonzero(fast.polarity) > 0


def test_selector_adapter_uses_fused_motion():
    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))

    sel = MapPolaritySelector(PolarityPredictor(), cmap, K, _MovingAlongX(T))
    idx = np.arange(0, len(cmap), 3)
    pol = sel(T, 1000, idx)
    assert pol.shape == idx.shape and pol.dtype == np.int8
    assert sel.last_counts["points"] == idx.size
    assert sel.last_counts["points_single_polarity"] + sel.last_counts["points_both"] == idx.size
    # Events on a predicted-ON point: ON kept, OFF removed; far away: outside every patch.
    from evpose.core.events import EventArray

    k = int(np.flatnonzero(pol == 1)[0])
    uv = _project(cmap.points[idx[k : k + 1]], T)[0]
    ev = EventArray.from_arrays([1, 2, 3], [round(uv[0])] * 2 + [0], [round(uv[1])] * 2 + [0], np.array([1, -1, 1], np.int8))
    label = sel.observe(ev, T, idx, pol, W, H)
    assert label.tolist() == [1, 0, -1]
    assert sel.last_counts["events_removed"] == 1


def test_learned_signs_survive_snapshot_and_restore():
    rng = np.random.default_rng(13)
    cmap = _square_map()
    pr = PolarityPredictor(PolarityFilterConfig(learn_min_votes=1))
    x, y, p, pred, label, point = _trial(rng, cmap, pr, use_map_sign=False)
    pr.learn(np.arange(len(cmap)), observed_point_polarity(point, p, len(cmap)))
    snap = pr.snapshot()
    learned = pr.learned_sign(np.arange(len(cmap)))
    assert np.count_nonzero(learned) > 0
    pr.learn(np.arange(len(cmap)), -observed_point_polarity(point, p, len(cmap)) * 5)
    pr.restore(snap)
    assert np.array_equal(pr.learned_sign(np.arange(len(cmap))), learned)


def test_fused_prediction_kernel_matches_the_image_motion_formulas():
    from evpose.fusion.polarity import PolarityFilterConfig, image_motion

    rng = np.random.default_rng(4)
    K = np.array([[200.0, 0, 173], [0, 201.0, 130], [0, 0, 1]])
    P = rng.normal(size=(400, 3)) * 2 + [0, 0, 4]
    P[:5, 2] = -1.0  # behind the camera
    n = rng.normal(size=(400, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.05, -0.1, 0.02]).as_matrix()
    T[:3, 3] = [0.1, -0.2, 0.05]
    c = PolarityFilterConfig()
    for omega, v in [(np.array([0.3, -0.2, 0.5]), np.array([0.4, 0.1, -0.2])), (np.zeros(3), np.zeros(3))]:
        pred = PolarityPredictor(c).predict_full(P, n, np.ones(400, np.int8), T, omega, v, K)
        n_img, flow, Z = image_motion(P, n, T, omega, v, K)
        speed = np.hypot(flow[:, 0], flow[:, 1])
        gnorm = np.hypot(n_img[:, 0], n_img[:, 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            cosang = (n_img * flow).sum(1) / (gnorm * speed)
            vis = gnorm * Z / (0.5 * (K[0, 0] + K[1, 1]))
        angle = np.degrees(np.arccos(np.clip(cosang, -1, 1)))
        buffer = np.minimum(c.buffer_deg + np.degrees(np.arctan2(c.flow_sigma_px_s, speed)), c.max_buffer_deg)
        np.testing.assert_allclose(pred.speed_px_s, speed, rtol=1e-6)
        np.testing.assert_allclose(pred.angle_deg, angle, rtol=1e-5, atol=1e-4, equal_nan=True)
        np.testing.assert_allclose(pred.buffer_deg, buffer, rtol=1e-6)
        reliable = np.isfinite(angle) & (Z > 0) & (speed >= c.min_image_speed_px_s) & (vis >= c.min_gradient_visibility)
        clear = reliable & (np.abs(np.abs(angle - 90) - buffer) > 1e-6)  # away from the decision boundary
        want = np.where(np.abs(angle - 90) > buffer, np.where(angle > 90, 1, -1), 0)
        assert np.array_equal(pred.geometric[clear], want[clear])
        assert np.all(pred.geometric[~reliable] == 0)
        if not omega.any():
            assert np.all(pred.polarity == 0)  # no motion: no prediction


def test_predict_full_on_rows_of_the_map_equals_predicting_the_gathered_points_bit_for_bit():
    """``rows`` reads the map's arrays in place (float32 normals widened in the kernel): the same prediction, geometry
    and learned-sign lookup as on the gathered float64 copies, and rows out of range are refused."""
    import pytest

    rng = np.random.default_rng(7)
    n_map = 600
    P = rng.normal(size=(n_map, 3)) * 2 + [0, 0, 4]
    nrm = rng.normal(size=(n_map, 3))
    nrm = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True)).astype(np.float32)
    sign = rng.choice(np.array([-1, 0, 1], np.int8), n_map)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.05, -0.1, 0.02]).as_matrix()
    rows = rng.choice(n_map, 250, replace=False).astype(np.int64)
    omega, v = np.array([0.3, -0.2, 0.5]), np.array([0.4, 0.1, -0.2])
    gathered, in_place = PolarityPredictor(), PolarityPredictor()
    votes = rng.integers(-5, 6, n_map).astype(np.int32)
    for p in (gathered, in_place):  # some learned signs, so the vote lookup by point index is exercised too
        p._votes = votes.copy()
    a = gathered.predict_full(P[rows], nrm[rows], sign[rows], T, omega, v, K, rows)
    b = in_place.predict_full(P, nrm, sign, T, omega, v, K, rows, rows=rows)
    for name in ("polarity", "angle_deg", "speed_px_s", "buffer_deg", "geometric"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert np.count_nonzero(a.polarity) > 50
    with pytest.raises(IndexError):
        in_place.predict_full(P, nrm, sign, T, omega, v, K, rows=np.array([0, n_map]))


def _selector_with_dropped_points():
    """A selector whose last step dropped the points of a square map that show no event (one ON event on one point)."""
    from evpose.core.events import EventArray
    from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))

    sel = MapPolaritySelector(PolarityPredictor(PolarityFilterConfig(drop_empty_points=True, learn_min_votes=1)), cmap, K, _MovingAlongX(T))
    idx = np.arange(0, len(cmap), 3)
    pol = sel(T, 60_000, idx)
    k = int(np.flatnonzero(pol == 1)[0])
    uv = _project(cmap.points[idx[k : k + 1]], T)[0]
    ev = EventArray.from_arrays([59_000], [round(uv[0])], [round(uv[1])], np.array([-1], np.int8))  # of the other polarity
    surface = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    surface.update(ev)
    sel.align(surface, cmap.points[idx], T, pol, None, ev, None, 60_000)
    keep = sel.points_to_register()
    return sel, idx, pol, keep, ev, T, k


def test_dropping_empty_points_keeps_the_contradicted_point_and_learns_over_all_points():
    sel, idx, pol, keep, ev, T, k = _selector_with_dropped_points()
    # The point's patch shows only an OFF event: it is reopened (both polarities), so it is kept, not dropped.
    assert keep is not None and keep[k] and np.count_nonzero(keep) < keep.size
    label = sel.observe(ev, T, idx[keep], pol[keep], W, H)  # the tracker passes the registered subset
    assert label.tolist() == [1]
    # The vote went to the map point it belongs to, found on the step's full grid.
    assert sel.predictor.learned_sign(idx[k : k + 1])[0] != 0


def test_observe_with_the_batch_and_its_keep_mask_labels_and_learns_as_with_the_kept_events():
    from evpose.core.events import EventArray
    from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))

    idx = np.arange(0, len(cmap), 2)
    rng = np.random.default_rng(3)
    uv = _project(cmap.points[idx], T)
    pick = rng.integers(0, idx.size, 300)
    x = np.clip(np.round(uv[pick, 0] + rng.integers(-2, 3, 300)), 0, W - 1)
    y = np.clip(np.round(uv[pick, 1] + rng.integers(-2, 3, 300)), 0, H - 1)
    ev = EventArray.from_arrays(np.arange(59_000, 59_300), x, y, rng.choice(np.array([-1, 1], np.int8), 300))
    keep = rng.random(300) < 0.8
    runs = []
    for with_mask in (True, False):
        sel = MapPolaritySelector(PolarityPredictor(PolarityFilterConfig(learn_min_votes=1)), cmap, K, _MovingAlongX(T))
        pol = sel(T, 60_000, idx)
        surface = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
        surface.update(ev, keep)
        sel.align(surface, cmap.points[idx], T, pol, None, ev, keep, 60_000)
        label = sel.observe(ev, T, idx, pol, W, H, keep=keep) if with_mask else sel.observe(ev[keep], T, idx, pol, W, H)
        runs.append((np.array(label), sel.predictor.learned_sign(idx), dict(sel.last_counts)))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1]) and runs[0][2] == runs[1][2]
    assert (runs[0][0] == 1).any() and np.count_nonzero(runs[0][1]) > 0


def test_registration_covariance_keeps_the_dropped_points_share_of_the_residual_variance():
    from types import SimpleNamespace

    from evpose.tracker.registration_config import RegistrationConfig, ResidualVariance

    sel, idx, pol, keep, ev, T, k = _selector_with_dropped_points()
    dropped = int(keep.size - np.count_nonzero(keep))
    cov = np.diag([1e-6] * 3 + [1e-4] * 3)
    reg = SimpleNamespace(covariance=cov, weights=np.array([1.0, 1.0, 0.0], np.float32), residuals=np.array([0.2, 0.1, 1.0], np.float32))
    cfg = RegistrationConfig()  # Huber, scale 0.3: a point reading TDF 1 adds w r^2 = 0.3
    out = sel.registration_covariance(reg, cfg)
    share = 0.2 ** 2 + 0.1 ** 2
    assert np.allclose(out, cov * (share + dropped * cfg.robust_scale) / share, rtol=1e-6)
    cfg.residual_variance = ResidualVariance.INLIERS  # dropped points never counted there: unchanged
    assert sel.registration_covariance(reg, cfg) is cov


def test_points_predicted_not_to_fire_are_left_out_of_registration_but_keep_learning():
    """``register_min_normal_speed_px_s``: with the camera moving along world x over a square, the two sides along x
    move along themselves (no normal flow) and are not registered, the two across x are; the covariance is not
    inflated for them (that is ``drop_empty_points``' empty patches), and observing still learns over every point."""
    from evpose.core.events import EventArray
    from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))
    cfg = PolarityFilterConfig(register_min_normal_speed_px_s=20.0, learn_min_votes=1)
    sel = MapPolaritySelector(PolarityPredictor(cfg), cmap, K, _MovingAlongX(T))
    idx = np.arange(0, len(cmap), 3)
    pol = sel(T, 60_000, idx)
    assert sel.points_to_register() is None  # no T_align yet this step
    surface = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    k = int(np.flatnonzero(pol != 0)[0])
    uv = _project(cmap.points[idx[k : k + 1]], T)[0]
    ev = EventArray.from_arrays([59_000], [round(uv[0])], [round(uv[1])], np.array([int(pol[k])], np.int8))
    surface.update(ev)
    sel.align(surface, cmap.points[idx], T, pol, None, ev, None, 60_000)
    keep = sel.points_to_register()
    across_x = np.abs(cmap.edge_normal[idx, 0]) > 0.5  # edge normal along the motion: the edge sweeps across pixels
    assert keep is not None and np.array_equal(keep, across_x)
    last = sel.predictor.last
    normal = last.speed_px_s * np.abs(np.cos(np.radians(last.angle_deg)))
    assert np.all(normal[keep] >= 20.0) and np.all(normal[~keep] < 20.0)

    class _Reg:
        covariance = np.eye(6)
        weights = np.ones(4, np.float32)
        residuals = np.full(4, 0.5, np.float32)

    from evpose.tracker.registration_config import RegistrationConfig

    assert np.array_equal(sel.registration_covariance(_Reg(), RegistrationConfig()), np.eye(6))
    label = sel.observe(ev, T, idx[keep], pol[keep], W, H)  # the tracker passes the registered subset
    assert label.tolist() == [1]
    assert sel.predictor.learned_sign(idx[k : k + 1])[0] != 0


def test_reopening_contradicted_points_only_without_fusion_follows_the_selectors_mode():
    """``reopen_contradicted_unfused``: a point whose patch shows only the other polarity is reopened when the pose is
    not the IMU fusion's (``stpe+filter``) and left as predicted when it is (``full``)."""
    from evpose.core.events import EventArray
    from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))
    reopened = {}
    for fused in (True, False):
        sel = MapPolaritySelector(PolarityPredictor(PolarityFilterConfig(reopen_contradicted_unfused=True)), cmap, K, _MovingAlongX(T))
        sel.fused_pose = fused
        idx = np.arange(0, len(cmap), 3)
        pol = sel(T, 60_000, idx)
        k = int(np.flatnonzero(pol == 1)[0])
        uv = _project(cmap.points[idx[k : k + 1]], T)[0]
        ev = EventArray.from_arrays([59_000], [round(uv[0])], [round(uv[1])], np.array([-1], np.int8))  # the other polarity
        surface = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
        surface.update(ev)
        sel.align(surface, cmap.points[idx], T, pol, None, ev, None, 60_000)
        reopened[fused] = sel.last_counts["points_reopened"]
    assert reopened == {True: 0, False: 1}


def test_while_held_every_point_takes_both_polarities_and_no_t_align_is_composed():
    from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig

    cmap = _square_map()
    T = _pose(0.0, np.array([0.0, 0.0, 2.0]), R_DOWN, np.zeros(3), np.zeros(3))
    sel = MapPolaritySelector(PolarityPredictor(), cmap, K, _MovingAlongX(T))
    sel.hold_updates = 1
    idx = np.arange(0, len(cmap), 3)
    surface = SeparatedTimeSurface(TimeSurfaceConfig(), W, H)
    held = sel(T, 1000, idx)
    assert not held.any() and sel.align(surface, cmap.points[idx], T, held, None) is None and sel.hold_updates == 0
    free = sel(T, 1000, idx)  # the hold is over: the motion predicts single polarities again
    assert free.any() and sel.align(surface, cmap.points[idx], T, free, None) is not None
