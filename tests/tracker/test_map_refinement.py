"""Online refinement of painted edges: which points count as painted, convergence onto the field's edge, bounds,
and bit-identical snapshot/restore inside the tracker."""

import numpy as np
import pytest
from tracker_synthetic import assert_restore_replays_bit_identically, generate

from evpose.core.contour_map import ContourMap
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.tracker.config import TrackerConfig
from evpose.tracker.map_refinement import MapRefinementConfig, PaintedEdgeRefiner, painted_points
from evpose.tracker.tracker import Tracker

W, H, F = 120, 90, 100.0
K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1.0]])
DOWN = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 2.0], [0, 0, 0, 1.0]])
"""Camera 2 m above the ground looking straight down (x right = world x)."""


def line_field(u_edge: float) -> TemporalDistanceField:
    """A field that is 0 on the image column ``u_edge`` and rises by 0.25 per pixel away from it (a fired edge)."""
    fld = TemporalDistanceField(DistanceFieldConfig(), W, H)
    u = np.arange(W, dtype=np.float64)
    img = np.minimum(np.abs(u - u_edge) * 0.25, 1.0).astype(np.float32)
    fld.value[0] = img[None, :]
    fld.grad_u[0] = np.gradient(img)[None, :]
    fld.grad_v[0] = 0.0
    fld.box[:] = (0, H, 0, W)
    return fld


def painted_line(x: float, n: int = 20, **attributes) -> ContourMap:
    y = np.linspace(-0.3, 0.3, n)
    pts = np.stack([np.full(n, x), y, np.zeros(n)], axis=1)
    normal = np.tile([1.0, 0.0, 0.0], (n, 1))
    attrs = dict(edge_normal=normal, brightness_sign=np.ones(n), curvature=np.zeros(n))
    attrs.update(attributes)
    return ContourMap.from_points(pts, **attrs)


def test_painted_points_have_a_brightness_sign_a_flat_surface_and_an_edge_normal():
    n = 4
    cmap = ContourMap.from_points(np.zeros((n, 3)), brightness_sign=[1, 0, -1, 1], curvature=[0.0, 0.0, 0.0, 0.2],
                                  edge_normal=[[1, 0, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0]])
    assert painted_points(cmap, 0.005).tolist() == [0]  # 1 unsigned, 2 without a normal, 3 curved
    cmap = ContourMap.from_points(np.zeros((n, 3)), brightness_sign=[1, 0, -1, 1], curvature=[0.0, 0.0, 0.0, 0.001],
                                  edge_normal=[[1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]])
    assert painted_points(cmap, 0.005).tolist() == [0, 2, 3]


def test_a_displaced_painted_edge_moves_onto_the_edge_the_field_shows():
    # The map puts the edge 2 cm (1 px at 2 m) right of where the field has it; steps are clipped, so it walks over.
    u_edge = (W - 1) / 2
    cmap = painted_line(0.02)
    refiner = PaintedEdgeRefiner(MapRefinementConfig(gain=0.2), cmap)
    pts = np.array(cmap.points)
    fld = line_field(u_edge)
    assert refiner.update(pts, fld, DOWN, K) == len(cmap)
    for _ in range(100):
        refiner.update(pts, fld, DOWN, K)
    # It stops where the field's slope falls below min_gradient: within 0.2 px of the edge, from 1 px.
    u = F * pts[:, 0] / 2.0 + K[0, 2]
    assert np.allclose(u, u_edge, atol=0.2)
    assert np.allclose(refiner.offsets, -0.02, atol=0.004)
    assert np.array_equal(pts[:, 1:], cmap.points[:, 1:])  # only along the normal


def test_a_step_the_given_pose_change_explains_is_not_taken():
    # A camera translation along world x of t moves the points by -F t / 2 = -50 t px: with the step the refiner
    # measures without a gauge (1 px right of the field's edge), the gauge that explains it all, or half of it.
    cfg = MapRefinementConfig(gain=1.0, step_clip_px=5.0, first_updates=0)
    cmap, fld = painted_line(0.02), line_field((W - 1) / 2)

    def offsets(gauge):
        refiner = PaintedEdgeRefiner(cfg, cmap)
        refiner.update(np.array(cmap.points), fld, DOWN, K, gauge)
        return refiner.offsets

    free = offsets(None)
    assert np.all(free < -0.01)  # towards the edge (1 px = 2 cm)
    step_px = free[0] * 50.0
    gauge = np.array([0.0, 0.0, 0.0, -step_px / 50.0, 0.0, 0.0])
    assert np.abs(offsets(gauge)).max() < 1e-9
    assert np.allclose(offsets(0.5 * gauge), 0.5 * free)


def test_offsets_stay_within_max_offset_and_points_without_events_do_not_move():
    cmap = painted_line(0.3)  # 15 px from the edge: the field reads 1 there, nothing to refine against
    refiner = PaintedEdgeRefiner(MapRefinementConfig(gain=1.0), cmap)
    pts = np.array(cmap.points)
    assert refiner.update(pts, line_field((W - 1) / 2), DOWN, K) == 0
    assert np.array_equal(pts, cmap.points)
    cmap = painted_line(0.05)
    refiner = PaintedEdgeRefiner(MapRefinementConfig(gain=1.0, max_offset_m=0.01, step_clip_px=5.0), cmap)
    pts = np.array(cmap.points)
    for _ in range(20):
        refiner.update(pts, line_field((W - 1) / 2), DOWN, K)
    assert np.allclose(refiner.offsets, -0.01)


@pytest.fixture(scope="module")
def painted_scene():
    rec, cmap, _ = generate(duration_s=0.2, seed=1)
    n = len(cmap)
    # Mark every point painted with an arbitrary normal: the refiner then moves them on every update.
    marked = ContourMap.from_points(cmap.points, edge_normal=np.tile([1.0, 0.0, 0.0], (n, 1)), brightness_sign=np.ones(n))
    return rec, marked


def test_tracker_refines_a_copy_of_the_map_and_restores_it_bit_identically(painted_scene):
    rec, cmap = painted_scene
    before = cmap.points.copy()

    def started():
        tr = Tracker(TrackerConfig(), cmap, rec.calibration)
        tr.start(rec.ground_truth.matrix(0), int(rec.ground_truth.t[0]))
        return tr

    straight = assert_restore_replays_bit_identically(started, rec.events)
    assert any(r.counts.get("points_refined", 0) > 0 for r in straight)
    assert np.array_equal(cmap.points, before)  # the map itself is never moved


def test_a_points_first_updates_take_a_running_mean_then_the_fixed_gain():
    # 1 m along x is 50 px at 2 m with f = 100 px: a clipped 0.25 px step is 5 mm.
    u_edge = (W - 1) / 2
    fld = line_field(u_edge)
    steps = {}
    for first in (0, 3):
        cmap = painted_line(0.04)
        refiner = PaintedEdgeRefiner(MapRefinementConfig(gain=0.1, first_updates=first), cmap)
        pts = np.array(cmap.points)
        offs = []
        for _ in range(4):
            refiner.update(pts, fld, DOWN, K)
            offs.append(refiner.offsets[0])
        steps[first] = -np.diff(np.concatenate([[0.0], offs]))
    assert np.allclose(steps[0], 0.1 * 0.005)
    assert np.allclose(steps[3], [0.005, 0.005 / 2, 0.005 / 3, 0.1 * 0.005])


def test_painted_points_are_held_out_of_registration_until_refined_register_after_updates_times():
    u_edge = (W - 1) / 2
    cmap = painted_line(0.02)
    refiner = PaintedEdgeRefiner(MapRefinementConfig(register_after_updates=3), cmap)
    assert refiner.held_out() is not None and refiner.held_out().all()
    pts = np.array(cmap.points)
    fld = line_field(u_edge)
    for k in range(3):
        assert refiner.held_out() is not None, k
        refiner.update(pts, fld, DOWN, K)
    assert refiner.held_out() is None  # every point refined 3 times: all registered
    # Points that never saw an event stay held; a restore re-derives the mask from the counts.
    far = PaintedEdgeRefiner(MapRefinementConfig(register_after_updates=3), painted_line(0.3))
    far.update(np.array(far._base), fld, DOWN, K)
    assert far.held_out().all()
    far.restore(refiner.snapshot())
    assert far.held_out() is None
    assert PaintedEdgeRefiner(MapRefinementConfig(register_after_updates=0), cmap).held_out() is None


def _stpe_points_used(cmap, rec, register_after_updates):
    from evpose.tracker.config import TrackerMode

    cfg = TrackerConfig(mode=TrackerMode.STPE)
    cfg.map_refinement.register_after_updates = register_after_updates
    tr = Tracker(cfg, cmap, rec.calibration)
    tr.start(rec.ground_truth.matrix(0), int(rec.ground_truth.t[0]))
    return tr.step(5_000, rec.events.time_window(0, 5_000)).counts["points_used"]


def test_stpe_registers_a_mostly_painted_view_from_the_start_but_holds_a_few_painted_points_back(painted_scene):
    rec, marked = painted_scene
    # Every point painted: holding them back would leave nothing to register, so none is.
    assert _stpe_points_used(marked, rec, 10) == _stpe_points_used(marked, rec, 0) > 0
    # A quarter painted: those are skipped until refined.
    n = len(marked)
    sign = np.where(np.arange(n) % 4 == 0, 1, 0)
    some = ContourMap.from_points(marked.points, edge_normal=marked.edge_normal, brightness_sign=sign)
    assert _stpe_points_used(some, rec, 10) < _stpe_points_used(some, rec, 0)
