"""Gauge-free online edge offsets: a pose-like disagreement between map and field is not learned, one edge's own
offset is; offsets are measured where registration samples the field; the tracker runs it on coarse sensors in each
mode whose switch is on (the filter modes from ``T_align``) and restores it bit-identically."""

import numpy as np
from tracker_synthetic import assert_restore_replays_bit_identically, box_edges, generate

from evpose.bench.registration_bias import true_edge_map
from evpose.core.contour_map import ContourMap
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.edge_offsets import EdgeOffsetConfig, EdgeOffsetLearner
from evpose.tracker.modes import MotionComponents
from evpose.tracker.tracker import Tracker

W, H, F = 160, 120, 100.0
K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1.0]])
DOWN = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 2.0], [0, 0, 0, 1.0]])
"""Camera 2 m above the ground looking straight down: world x = image u, world y = -image v, 50 px per metre."""
XS = tuple(np.linspace(-1.4, 1.4, 12))
"""Lines x = const (image columns) for y in ``X_LINES_Y``."""
YS = tuple(np.linspace(-1.0, -0.3, 5))
"""Lines y = const (image rows) for x in ``Y_LINES_X``: apart from the x lines, so no point sees two lines' fields."""
X_LINES_Y = (0.0, 1.0)
Y_LINES_X = (-1.5, 1.5)
FLOOR, BOWL = 0.3, 0.1
"""The field: ``FLOOR + BOWL d^2`` at ``d`` pixels from its nearest line (a blurred edge's smooth, non-zero minimum)."""


def grid_map(shift_first_m: float = 0.0) -> ContourMap:
    """The lines on the ground, normals +x / +y; the first x line moved by ``shift_first_m`` along its normal."""
    s = np.linspace(0.0, 1.0, 21)
    pts, normals, tangents = [], [], []
    for k, x in enumerate(XS):
        y = X_LINES_Y[0] + s * (X_LINES_Y[1] - X_LINES_Y[0])
        pts.append(np.stack([np.full(s.size, x + (shift_first_m if k == 0 else 0.0)), y, np.zeros(s.size)], axis=1))
        normals.append(np.tile([1.0, 0.0, 0.0], (s.size, 1)))
        tangents.append(np.tile([0.0, 1.0, 0.0], (s.size, 1)))
    for y in YS:
        x = Y_LINES_X[0] + s * (Y_LINES_X[1] - Y_LINES_X[0])
        pts.append(np.stack([x, np.full(s.size, y), np.zeros(s.size)], axis=1))
        normals.append(np.tile([0.0, 1.0, 0.0], (s.size, 1)))
        tangents.append(np.tile([-1.0, 0.0, 0.0], (s.size, 1)))
    n, t = np.concatenate(normals), np.concatenate(tangents)
    return ContourMap.from_points(np.concatenate(pts), edge_normal=n, plane_normal=np.cross(n, t))


def grid_field(du_px: float = 0.0, dv_px: float = 0.0) -> TemporalDistanceField:
    """The field of the true lines seen from ``DOWN`` (shifted in the image by ``du_px`` / ``dv_px``), see ``BOWL``."""
    fld = TemporalDistanceField(DistanceFieldConfig(), W, H)
    u = np.arange(W, dtype=np.float64)[None, :]
    v = np.arange(H, dtype=np.float64)[:, None]
    uc, vc = K[0, 2] + du_px, K[1, 2] + dv_px
    d = np.full((H, W), np.inf)
    for x in XS:  # world y -> image v = vc - 50 y
        col = F * x / 2.0 + uc
        v0, v1 = vc - F * X_LINES_Y[1] / 2.0, vc - F * X_LINES_Y[0] / 2.0
        d = np.minimum(d, np.hypot(u - col, np.maximum(np.maximum(v0 - v, v - v1), 0.0)))
    for y in YS:
        row = vc - F * y / 2.0
        u0, u1 = uc + F * Y_LINES_X[0] / 2.0, uc + F * Y_LINES_X[1] / 2.0
        d = np.minimum(d, np.hypot(v - row, np.maximum(np.maximum(u0 - u, u - u1), 0.0)))
    img = np.minimum(FLOOR + BOWL * d**2, 1.0).astype(np.float32)
    fld.value[0] = img
    fld.grad_u[0] = np.gradient(img, axis=1)
    fld.grad_v[0] = np.gradient(img, axis=0)
    fld.box[:] = (0, H, 0, W)
    return fld


def learner_for(cmap: ContourMap, **config) -> EdgeOffsetLearner:
    tangents = np.cross(cmap.plane_normal, cmap.edge_normal)
    return EdgeOffsetLearner(EdgeOffsetConfig(**config), cmap.points, cmap.edge_normal, tangents)


def test_a_disagreement_a_pose_change_explains_is_not_learned():
    # The field shows every line 0.4 px right and 0.3 px down: a camera shift, which registration must take.
    cmap = grid_map()
    learner = learner_for(cmap, gain=1.0)
    pts = np.array(cmap.points)
    fld = grid_field(0.4, 0.3)
    for _ in range(20):
        assert learner.update(pts, np.arange(len(cmap)), fld, DOWN, K) == len(cmap)
    assert np.abs(learner.offsets).max() < 1e-4  # < 0.005 px of the 0.5 px (1 cm) disagreement
    assert np.allclose(learner.last_fit[3:5], [-0.4 * 0.02, -0.3 * 0.02], rtol=0.1)  # the fit takes it as the shift
    assert np.array_equal(pts, cmap.points + learner.offsets[:, None] * cmap.edge_normal)


def test_one_edge_displaced_against_the_others_moves_until_only_a_pose_like_disagreement_is_left():
    # The first x line is mapped 0.5 px (1 cm) right of where the field has it; the other lines are right.
    cmap = grid_map(shift_first_m=0.01)
    learner = learner_for(cmap, gain=0.5)
    pts = np.array(cmap.points)
    fld = grid_field()
    for _ in range(40):
        learner.update(pts, np.arange(len(cmap)), fld, DOWN, K)
    first = np.arange(len(cmap)) < 21
    # In one view of a flat scene part of a border line's shift looks like a pose change (scale, tilt): that part
    # stays, spread over the map as a pose-like pattern; the rest is learned.
    assert np.all(learner.offsets[first] < -0.004)
    assert np.median(np.abs(learner.offsets[~first])) < 0.001
    assert np.allclose(np.cross(pts - cmap.points, cmap.edge_normal), 0.0)  # only along the normals
    before = learner.offsets.copy()
    learner.config.gain = 1.0
    learner.update(pts, np.arange(len(cmap)), fld, DOWN, K)
    assert np.abs(learner.offsets - before).max() < 1e-4  # nothing left that no pose explains
    assert np.linalg.norm(learner.last_fit) > 1e-3


def test_offsets_are_measured_where_registration_reads_the_field():
    # The first x line is mapped 0.5 px right of its field, and registration reads its field 0.5 px behind it
    # (a per-point trail, as the fused modes' polarity trail): from there the field is at its minimum.
    cmap = grid_map(shift_first_m=0.01)
    first = np.arange(len(cmap)) < 21
    trail = np.where(first, 0.5, 0.0)
    still = np.zeros(6)  # no motion: the trail points along the image normal (+u for the x lines)
    learner = learner_for(cmap, gain=0.5)
    pts = np.array(cmap.points)
    for _ in range(20):
        assert learner.update(pts, np.arange(len(cmap)), grid_field(), DOWN, K, still, 0.0045, 0.0, trail) == len(cmap)
    assert np.abs(learner.offsets).max() < 2e-4  # nothing to learn (the same map without the trail: < -0.004 m)
    # A lag floor with no motion reads every line's field 0.5 px behind it: a camera shift, nothing to learn either.
    learner = learner_for(cmap, gain=0.5)
    pts = np.array(cmap.points)
    for _ in range(20):
        learner.update(pts, np.arange(len(cmap)), grid_field(), DOWN, K, still, 0.0045, 0.5, trail)
    assert np.abs(learner.offsets).max() < 2e-4
    # Without the twist there is no shift (as in registration): the first line's displacement is learned.
    learner = learner_for(cmap, gain=0.5)
    pts = np.array(cmap.points)
    for _ in range(20):
        learner.update(pts, np.arange(len(cmap)), grid_field(), DOWN, K, None, 0.0045, 0.5, trail)
    assert np.all(learner.offsets[first] < -0.004)


def test_points_whose_offset_exceeds_the_clip_or_whose_edge_did_not_fire_take_no_part():
    cmap = grid_map()
    learner = learner_for(cmap, step_clip_px=0.2)
    pts = np.array(cmap.points)
    assert learner.update(pts, np.arange(len(cmap)), grid_field(0.4, 0.0), DOWN, K) == len(YS) * 21  # x lines dropped
    far = TemporalDistanceField(DistanceFieldConfig(), W, H)  # reads 1 everywhere: no edge fired
    far.box[:] = (0, H, 0, W)
    assert learner_for(cmap).update(np.array(cmap.points), np.arange(len(cmap)), far, DOWN, K) == 0


def _box_map() -> ContourMap:
    return true_edge_map(box_edges(), 0.01)[0]


def test_the_tracker_learns_offsets_only_on_coarse_sensors_with_each_modes_switch_and_restores_them_bit_identically():
    rec, _, _ = generate(duration_s=0.2, seed=1)
    cmap = _box_map()
    assert 1e3 / rec.calibration.K[0, 0] >= EdgeOffsetConfig().min_pixel_mrad  # 240 px over 100 deg: a coarse sensor

    def started(mode=TrackerMode.STPE, min_pixel_mrad=None):
        cfg = TrackerConfig(mode=mode)
        if min_pixel_mrad is not None:
            cfg.edge_offsets.min_pixel_mrad = min_pixel_mrad
        tr = Tracker(cfg, cmap, rec.calibration)
        tr.start(rec.ground_truth.matrix(0), int(rec.ground_truth.t[0]))
        return tr

    # Where a fusion drives the pose and behind the polarity filter each mode has its own switch and lag.
    off = TrackerConfig()
    off.edge_offsets.full = off.edge_offsets.stpe_filter = False
    assert Tracker(off, cmap, rec.calibration, components=MotionComponents(drives_pose=True)).edge_offsets is None
    assert Tracker(off, cmap, rec.calibration, polarity_selector=lambda T, t, idx: None).edge_offsets is None
    fused = Tracker(TrackerConfig(), cmap, rec.calibration, components=MotionComponents(drives_pose=True))
    assert fused.edge_offsets is not None and fused._registration.field_lag_ms == EdgeOffsetConfig().full_field_lag_ms
    filtered = Tracker(TrackerConfig(), cmap, rec.calibration, polarity_selector=lambda T, t, idx: None)
    assert filtered._registration.field_lag_ms == EdgeOffsetConfig().stpe_filter_field_lag_ms
    assert started(min_pixel_mrad=10.0).edge_offsets is None
    bare = ContourMap.from_points(cmap.points)  # no edge directions: nothing to learn, and the config's lag stays
    tr = Tracker(TrackerConfig(), bare, rec.calibration)
    assert tr.edge_offsets is None and tr._registration.field_lag_ms == TrackerConfig().registration.field_lag_ms
    assert started()._registration.field_lag_ms == EdgeOffsetConfig().field_lag_ms
    straight = assert_restore_replays_bit_identically(started, rec.events)
    assert any(r.counts.get("points_offset", 0) > 0 for r in straight)
    assert np.array_equal(cmap.points, _box_map().points)  # the map itself is never moved


def test_in_the_filter_modes_the_offsets_are_learned_from_t_align_with_their_own_switch_and_lag(sim_landing_small):
    import dataclasses

    from evpose.tracker.session import TrackingSession

    rec = sim_landing_small.recording
    rec = dataclasses.replace(rec, events=rec.events.time_window(int(rec.events.t[0]), int(rec.events.t[0]) + 300_000))
    cmap = true_edge_map(sim_landing_small.edges, 0.02)[0]
    for mode, switch in ((TrackerMode.STPE_FILTER, "stpe_filter"), (TrackerMode.FULL, "full")):
        cfg = TrackerConfig(mode=mode)
        cfg.edge_offsets.min_pixel_mrad = 0.0
        setattr(cfg.edge_offsets, switch, False)
        assert TrackingSession(rec, cmap, cfg).tracker.edge_offsets is None  # its own switch
        setattr(cfg.edge_offsets, switch, True)
        setattr(cfg.edge_offsets, f"{switch}_field_lag_ms", 5.2)
        s = TrackingSession(rec, cmap, cfg)
        assert s.tracker._registration.field_lag_ms == 5.2  # the mode's own lag while learning, not stpe's
        s.run()
        # Registration read T_align (one field, the used points' patches): the learner reads the same field.
        learned = [r for r in s.results if r.counts.get("points_offset", 0) > 0]
        assert learned and all("events_outside_patches" in r.counts for r in learned)
        assert np.any(s.tracker.edge_offsets.offsets != 0)
        assert np.array_equal(cmap.points, true_edge_map(sim_landing_small.edges, 0.02)[0].points)  # never the map
