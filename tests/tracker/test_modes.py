"""The tracker modes on a simulated landing with IMU: stpe, stpe+filter, full (factor graph / EKF / IMU-only)."""

from __future__ import annotations

import numpy as np
import pytest

from evpose.core.contour_map import ContourMap
from evpose.eval.metrics import Alignment, EvalConfig, evaluate
from evpose.fusion import FusionBackend
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.modes import build_motion_components
from evpose.tracker.session import TrackingSession
from evpose.tracker.step_result import TrackStatus

SECONDS = 0.5


@pytest.fixture(scope="module")
def landing(landing_head):
    """The first half second of the small simulated landing and a map sampled along its true edges (2 cm)."""
    return landing_head(SECONDS)


def _run(rec, cmap, mode, backend=FusionBackend.FACTOR_GRAPH):
    cfg = TrackerConfig(mode=mode)
    cfg.fusion.backend = backend
    s = TrackingSession(rec, cmap, cfg)
    s.run()
    return s


def _ate_mm(session, rec):
    return evaluate(session.trajectory(), rec.ground_truth, EvalConfig(align=Alignment.NONE)).ate["rmse"] * 1e3


def test_full_mode_fuses_the_imu_and_beats_registration_alone(landing):
    rec, cmap = landing
    stpe = _run(rec, cmap, TrackerMode.STPE)
    full = _run(rec, cmap, TrackerMode.FULL)
    r = full.results[-1]
    assert r.velocity is not None and r.velocity.shape == (3,)
    assert r.covariance is not None and r.covariance.shape == (6, 6)
    assert "fusion" in r.timings_ms
    assert all(x.status in (TrackStatus.OK, TrackStatus.DEGRADED) for x in full.results)
    assert _ate_mm(full, rec) < _ate_mm(stpe, rec)


def test_full_mode_seek_back_replays_bit_identically(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.FULL, snapshot_every=10)
    s = TrackingSession(rec, cmap, cfg)
    ref = [x.pose.copy() for x in s.run()]
    r = s.seek(s.results[23].t_us)
    assert np.array_equal(r.pose, ref[23])
    s.run()
    assert all(np.array_equal(a.pose, b) for a, b in zip(s.results, ref))


def test_imu_only_backend_marks_every_pose_degraded(landing):
    rec, cmap = landing
    s = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL, fusion=_backend(FusionBackend.IMU_ONLY)))
    for _ in range(5):
        r = s.step()
    assert r.status is TrackStatus.DEGRADED and "dead reckoning" in r.reason


def _backend(backend):
    from evpose.fusion import FusionConfig

    return FusionConfig(backend=backend)


def test_debug_step_in_full_mode_carries_imu_rate_poses(landing):
    rec, cmap = landing
    s = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL))
    s.step()
    r = s.step(debug=True)
    assert r.imu_poses is not None and len(r.imu_poses) >= 1
    assert np.all(np.diff(r.imu_poses.t) > 0)


def test_polarity_filter_mode_labels_events_and_reports_counts(landing):
    rec, cmap = landing
    # Give the map points edge normals (perpendicular to the edge, horizontal) so polarity can be predicted;
    # their brightness signs are unknown and learned online.
    seg_dir = np.gradient(cmap.points, axis=0)
    normals = np.cross(seg_dir, [0.0, 0.0, 1.0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
    cm = ContourMap.from_points(cmap.points, edge_normal=normals)
    s = TrackingSession(rec, cm, TrackerConfig(mode=TrackerMode.STPE_FILTER))
    results = [s.step() for _ in range(30)]
    assert all("polarity_filter" in r.timings_ms and "events_polarity_removed" in r.counts for r in results)
    # The filter's time is reported per part (prediction, T_align, labelling): disjoint spans within its total.
    for r in results[1:]:
        t = r.timings_ms
        assert min(t["polarity_predict"], t["polarity_align"], t["polarity_observe"]) > 0
        assert t["polarity_predict"] + t["polarity_align"] + t["polarity_observe"] <= t["polarity_filter"] + 1e-9
    assert all(r.velocity is not None for r in results)
    # The event filter (T_align) judged every stored event and registered only points whose patch shows events.
    for r in results[1:]:
        c = r.counts
        assert c["events_polarity_judged"] <= c["events_kept"]
        assert c["events_polarity_removed"] == c["events_outside_patches"] + c["events_wrong_polarity"] <= c["events_polarity_judged"]
        assert c["points_registered"] == c["points_used"] and c["points_with_events"] <= c["points_used"]
    assert sum(r.counts["events_polarity_removed"] for r in results) > 0


def test_dropping_empty_points_registers_only_points_whose_patch_shows_events(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.FULL)
    cfg.polarity.drop_empty_points = True
    s = TrackingSession(rec, cmap, cfg)
    results = [s.step() for _ in range(10)]
    assert all(r.counts["points_registered"] == r.counts["points_with_events"] <= r.counts["points_used"] for r in results)
    assert any(r.counts["points_registered"] < r.counts["points_used"] for r in results)


def test_points_predicted_not_to_fire_are_not_registered_and_only_stpe_filter_reopens(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.STPE_FILTER)
    cfg.polarity.register_min_normal_speed_px_s = 200.0
    s = TrackingSession(rec, cmap, cfg)
    assert s.tracker.polarity_selector.fused_pose is False
    results = [s.step() for _ in range(10)]
    assert all(r.counts["points_registered"] <= r.counts["points_used"] for r in results)
    assert any(r.counts["points_registered"] < r.counts["points_used"] for r in results)
    assert TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL)).tracker.polarity_selector.fused_pose is True


def test_polarity_filter_off_registers_every_used_point_on_per_point_fields(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.STPE_FILTER)
    cfg.polarity.event_filter = False
    s = TrackingSession(rec, cmap, cfg)
    results = [s.step() for _ in range(5)]
    assert all("points_registered" not in r.counts and "events_outside_patches" not in r.counts for r in results)


def test_fused_mode_needs_imu(landing):
    import dataclasses

    from evpose.errors import InputError

    rec, cmap = landing
    with pytest.raises(InputError, match="needs IMU"):
        build_motion_components(TrackerConfig(mode=TrackerMode.FULL), cmap, rec.calibration, has_imu=False)
    bare = dataclasses.replace(rec, imu=None)
    with pytest.raises(InputError, match="needs IMU"):
        TrackingSession(bare, cmap, TrackerConfig(mode=TrackerMode.STPE_FILTER))


def test_ego_motion_filter_runs_before_the_time_surface_in_full_mode(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.FULL)
    cfg.ego_motion.enabled = True
    s = TrackingSession(rec, cmap, cfg)
    results = [s.step() for _ in range(20)]
    assert all("ego_motion" in r.timings_ms and "events_ego_removed" in r.counts for r in results)
    assert all(r.counts["events_ego_removed"] <= r.counts["events_in"] for r in results)
    assert all(r.status in (TrackStatus.OK, TrackStatus.DEGRADED) for r in results)


def test_full_mode_with_ego_motion_history_seek_back_replays_bit_identically(landing):
    # The ego-motion filter judges each batch against recent events: that history must be part of the snapshot.
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.FULL, snapshot_every=10)
    cfg.ego_motion.enabled = True
    s = TrackingSession(rec, cmap, cfg)
    ref = [(x.pose.copy(), x.counts["events_ego_removed"]) for x in s.run()]
    assert sum(c for _, c in ref) > 0
    s.seek(s.results[23].t_us)
    s.run()
    assert all(np.array_equal(a.pose, p) and a.counts["events_ego_removed"] == c for a, (p, c) in zip(s.results, ref))


def test_full_mode_takes_the_looser_inlier_test_only_once_the_map_is_acquired(landing):
    from evpose.tracker.track_hold import ACQUIRE_UPDATES

    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.FULL)
    cfg.registration.min_inlier_ratio, cfg.registration.fused_min_inlier_ratio = 0.99, 0.0
    never = TrackingSession(rec, cmap, cfg)
    never.run()
    # The loose test alone would pass every registration; without the strict one first, none is fused.
    assert all(r.counts["registered"] == 0 and r.reason.startswith("acquiring the map") for r in never.results)
    assert all(r.status is TrackStatus.DEGRADED for r in never.results) and not never.tracker.hold.acquired
    ok = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL))
    for _ in range(ACQUIRE_UPDATES):
        ok.step()
    assert ok.tracker.hold.acquired and all(r.counts["registered"] for r in ok.results)


def _recorded_trails(rec, cmap, mode, buffer_px, split_px=0.2, steps=8):
    """The per-point trail offsets registration got in the first ``steps`` updates, with the predicted polarities."""
    import evpose.tracker.tracker as tracker_module

    cfg = TrackerConfig(mode=mode)
    cfg.registration.fused_buffer_trail_px = buffer_px
    cfg.registration.fused_polarity_trail_px = split_px
    s = TrackingSession(rec, cmap, cfg)
    seen, original = [], tracker_module.register_to_map

    def recording(*args, trail_offsets_px=None, **kwargs):
        seen.append(None if trail_offsets_px is None else np.array(trail_offsets_px))
        return original(*args, trail_offsets_px=trail_offsets_px, **kwargs)

    tracker_module.register_to_map = recording
    try:
        polarities = [s.step(debug=True).debug.predicted_polarity for _ in range(steps)]
    finally:
        tracker_module.register_to_map = original
    return seen, polarities


def test_full_mode_samples_buffer_zone_points_further_behind_than_the_lag_model(landing, sim_landing_small):
    from evpose.bench.registration_bias import true_edge_map

    rec, _ = landing
    # Edge normals and a brightness sign let the polarity filter predict ON / OFF points besides its buffer zone.
    cmap = true_edge_map(sim_landing_small.edges, 0.02)[0]
    cmap.brightness_sign[:] = 1
    seen, polarities = _recorded_trails(rec, cmap, TrackerMode.FULL, buffer_px=0.1)
    assert len(seen) == len(polarities) and all(t is not None for t in seen)
    for trail, pol in zip(seen, polarities):
        assert trail.shape == pol.shape
        assert np.all(trail[pol == 0] == 0.1) and np.all(trail[pol > 0] == -0.1) and np.all(trail[pol < 0] == 0.1)
    assert any(np.any(p == 0) for p in polarities) and any(np.any(p != 0) for p in polarities)
    # Both terms off: no per-point trail at all; the polarity-filter mode without fusion never gets one.
    assert all(t is None for t in _recorded_trails(rec, cmap, TrackerMode.FULL, buffer_px=0.0, split_px=0.0, steps=3)[0])
    assert all(t is None for t in _recorded_trails(rec, cmap, TrackerMode.STPE_FILTER, buffer_px=0.1, steps=3)[0])


def test_stpe_filter_composes_held_out_painted_points_into_t_align_but_does_not_register_them(landing):
    rec, cmap = landing
    n = len(cmap)
    # A quarter of the points painted (a brightness sign, a flat surface, an edge normal): held out until refined.
    painted = ContourMap.from_points(cmap.points, edge_normal=np.tile([1.0, 0.0, 0.0], (n, 1)),
                                     brightness_sign=np.where(np.arange(n) % 4 == 0, 1, 0))

    def first_steps(hold):
        cfg = TrackerConfig(mode=TrackerMode.STPE_FILTER)
        cfg.map_refinement.hold_out_filtered = hold
        s = TrackingSession(rec, painted, cfg)
        return [s.step() for _ in range(5)]

    held, kept = first_steps(True), first_steps(False)
    for h, k in zip(held, kept):
        assert h.counts["points_used"] == k.counts["points_used"]  # the same points' patches make up T_align
        assert k.counts["points_registered"] == k.counts["points_used"]
        assert h.counts["points_registered"] < h.counts["points_used"]
    # Held points are still refined from their patches (T_align shows them), so they come back once placed.
    assert sum(r.counts.get("points_refined", 0) for r in held) > 0


def test_unfused_latest_motion_takes_the_gyro_and_steps_the_latest_fused_velocity_without_propagating(landing):
    rec, cmap = landing
    cfg = TrackerConfig(mode=TrackerMode.STPE_FILTER)
    assert cfg.polarity.unfused_latest_motion  # the default
    s = TrackingSession(rec, cmap, cfg)
    for _ in range(3):
        r = s.step()
    sel, motion = s.tracker.polarity_selector, s.tracker.components.motion
    assert sel.latest_state is motion
    cfg.mode = TrackerMode.FULL  # full predicts its pose by that propagation: the option leaves it alone
    assert TrackingSession(rec, cmap, cfg).tracker.polarity_selector.latest_state is None
    t = r.t_us + 5_000
    omega, v = sel._motion(t)
    last, fusion = motion.last, motion.fusion
    acc, gyro = fusion.buffer.measurement_at(t)
    assert np.array_equal(omega, fusion.extrinsic.cam_omega(gyro - last.gyro_bias))
    # The latest fused velocity moved on by one accelerometer step (specific force rotated to the world, plus gravity).
    acc_world = last.T_world_cam[:3, :3] @ fusion.extrinsic.R_cam_imu @ (acc - last.acc_bias) - [0.0, 0.0, fusion.config.gravity]
    assert np.allclose(v, last.velocity_world + acc_world * (t - last.t_us) * 1e-6, rtol=0, atol=1e-12)
    predicted = motion.fusion.predict(t)  # what the option replaces: the same rate, the velocity propagated 5 ms on
    assert np.allclose(omega, predicted.omega_cam)
    assert np.linalg.norm(v - predicted.velocity_world) < 0.5 * np.linalg.norm(last.velocity_world - predicted.velocity_world)
    assert np.array_equal(sel._motion(last.t_us)[1], last.velocity_world)  # no time since the state: no step
    sel.latest_state = None
    omega_p, v_p = sel._motion(t)
    assert np.array_equal(omega_p, predicted.omega_cam) and np.array_equal(v_p, predicted.velocity_world)
