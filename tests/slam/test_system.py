"""End-to-end SLAM on the synthetic point scene: accuracy, determinism, lost/re-initialisation, bad input."""

import numpy as np
import pytest

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.eval.slam_metrics import atlas_metrics
from evpose.errors import InputError
from evpose.slam import EventSlam, SlamConfig, SlamFailure, SlamMode, SlamStatus, run_slam
from slam_synthetic import make_recording

RADTAN = CameraCalibration(240, 180, 200, 200, 119.5, 89.5, "radtan", (-0.25, 0.07, 0.001, -0.001, 0.0))
KB = CameraCalibration(240, 180, 200, 200, 119.5, 89.5, "equidistant", (0.05, -0.01, 0.002, 0.0))


@pytest.fixture(scope="module")
def radtan_recording():
    return make_recording(duration_s=2.0, speed=1.5, calibration=RADTAN, seed=5)


@pytest.fixture(scope="module")
def radtan_run(radtan_recording):
    return run_slam(radtan_recording, SlamConfig())


def test_event_only_slam_tracks_most_of_the_recording_with_small_scale_aligned_error(radtan_recording, radtan_run):
    m = atlas_metrics(radtan_run.trajectories(), radtan_recording.ground_truth, correct_scale=True, duration_s=radtan_run.duration_s)
    assert len(m.maps) == 1
    assert m.tracked_fraction >= 0.8
    assert m.ate_percent <= 2.0
    statuses = [r.status for r in radtan_run.results]
    assert statuses[0] is SlamStatus.NOT_INITIALISED and statuses[-1] is SlamStatus.OK
    # Time under each status covers the recording; the events' own share (no coasting here) is the tracked one.
    by_status = radtan_run.time_by_status_s()
    assert sum(by_status.values()) == pytest.approx(radtan_run.duration_s)
    assert radtan_run.visual_fraction == pytest.approx(by_status["ok"] / radtan_run.duration_s)
    assert 0.8 <= radtan_run.visual_fraction <= m.tracked_fraction + 0.05
    kf = radtan_run.atlas.maps[0].keyframes
    assert len(kf) >= 3 and any(r.keyframe for r in radtan_run.results)
    # The viewer's products are filled in for tracked MCIs.
    r = radtan_run.results[-1]
    assert r.mci.shape == (180, 240) and r.features.shape[1] == 2 and r.map_points.shape[1] == 3
    assert set(r.hypothesis_scores) >= {"H2", "H4"} and r.hypothesis in r.hypothesis_scores


def test_parallax_hypothesis_joins_once_a_map_exists_and_only_where_enabled(radtan_recording):
    cfg = SlamConfig()
    cfg.mci.use_parallax = True
    run = run_slam(radtan_recording, cfg)
    m = atlas_metrics(run.trajectories(), radtan_recording.ground_truth, correct_scale=True, duration_s=run.duration_s)
    assert m.tracked_fraction >= 0.8 and m.ate_percent <= 2.0
    # H5 needs map depths: absent before the first map, tried on most MCIs after it.
    assert "H5" not in run.results[0].hypothesis_scores
    assert sum("H5" in r.hypothesis_scores for r in run.results) > len(run.results) // 2
    # Event-inertial runs take use_parallax_inertial (off) instead.
    inertial = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    inertial.mci.use_parallax = True
    slam = EventSlam(inertial, radtan_recording.calibration, radtan_recording.imu)
    assert not slam.mci_gen.cfg.use_parallax
    # ... and do not carry tiny-frame tracks for it.
    assert not slam.window.carry_tracks and EventSlam(cfg, radtan_recording.calibration).window.carry_tracks


def test_each_initial_pose_follows_its_own_keyframe(radtan_run):
    # The two-view pose at the first keyframe stays with it when later BAs move the second keyframe.
    m = radtan_run.atlas.maps[0]
    assert m.traj_ref[0] == m.keyframes[0].id and m.traj_ref[1] == m.keyframes[1].id
    # As the map holds it: the written trajectory re-places a map's first pose from its next poses
    # (TrackingConfig.first_pose_extrapolation_s).
    assert np.allclose(m.trajectory(refit=False).matrices()[0], m.keyframes[0].T_wc)


def test_slam_is_deterministic(radtan_recording, radtan_run):
    again = run_slam(radtan_recording, SlamConfig())
    a, b = radtan_run.trajectories(), again.trajectories()
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert np.array_equal(x.t, y.t) and np.array_equal(x.position, y.position) and np.array_equal(x.quat_xyzw, y.quat_xyzw)
    assert [r.hypothesis_scores for r in radtan_run.results] == [r.hypothesis_scores for r in again.results]


def _scene_switch_recording():
    """Kannala-Brandt camera; after 1.2 s the events stop for 0.2 s and resume on another scene: tracks jump to unrelated features and the map is lost."""
    a = make_recording(duration_s=1.2, speed=1.5, calibration=KB, seed=7)
    b = make_recording(duration_s=1.4, speed=1.5, calibration=KB, seed=8)
    shift = int(a.events.t[-1]) + 200_000
    ev = EventArray.concatenate([a.events, EventArray(b.events.t + shift, b.events.x, b.events.y, b.events.p)])
    return Recording(events=ev, calibration=KB)


@pytest.mark.parametrize("search", [False, True], ids=["klt-only", "with-projection-search"])
def test_lost_tracking_opens_a_new_map_in_the_atlas(search):
    # With the projection search on, the look-alike blobs of the new scene must not be "re-found" as the old map's points.
    cfg = SlamConfig()
    cfg.search.enabled = search
    run = run_slam(_scene_switch_recording(), cfg)
    statuses = [r.status for r in run.results]
    assert SlamStatus.LOST in statuses
    lost = statuses.index(SlamStatus.LOST)
    assert "lost" in run.results[lost].reason
    assert SlamStatus.OK in statuses[lost + 1 :], "the second scene must be re-initialised"
    maps = [m for m in run.atlas.maps if m.traj_t]
    assert len(maps) == 2 and maps[0].lost_reason
    assert maps[0].traj_t[-1] < maps[1].traj_t[0]
    assert run.results[-1].map_id == maps[1].id


def test_each_untracked_mci_says_why_and_tracked_ones_count_their_inliers():
    cfg = SlamConfig()
    run = run_slam(_scene_switch_recording(), cfg)
    for r in run.results:
        if r.status is SlamStatus.OK:
            assert r.failure is SlamFailure.NONE
        elif r.status is SlamStatus.NOT_INITIALISED:
            assert r.failure is SlamFailure.INITIALISING and r.counts["map_tracks"] == -1
        else:
            assert r.failure in (SlamFailure.STARVED, SlamFailure.REJECTED)
            assert (r.counts["map_tracks"] < cfg.tracking.min_inliers) == (r.failure is SlamFailure.STARVED)
    tracked = [r for r in run.results if r.status is SlamStatus.OK and r.counts["inliers"] >= 0]
    assert tracked and all(cfg.tracking.min_inliers <= r.counts["inliers"] <= r.counts["map_tracks"] for r in tracked)
    lost = next(r for r in run.results if r.status is SlamStatus.LOST)
    assert lost.failure is not SlamFailure.NONE
    assert run.time_by_failure_s().keys() >= {"initialising", lost.failure.value}


def test_still_camera_waits_with_a_reason_and_never_initialises():
    rec = make_recording(duration_s=0.5, still=True)
    slam = EventSlam(SlamConfig(), rec.calibration)
    res = slam.step(rec.events)
    assert res.status is SlamStatus.WAITING and "rate" in res.reason
    assert slam.atlas.maps == [] and slam.results == []


def test_empty_and_tiny_inputs_wait_without_error():
    rec = make_recording(duration_s=0.05, speed=1.0)
    slam = EventSlam(SlamConfig(), rec.calibration)
    assert slam.step(EventArray.empty()).status is SlamStatus.WAITING
    assert slam.step(rec.events[:100]).status is SlamStatus.WAITING


def test_event_inertial_mode_without_imu_is_an_input_error():
    rec = make_recording(duration_s=0.05)
    cfg = SlamConfig(mode=SlamMode.EVENT_INERTIAL)
    with pytest.raises(InputError, match="IMU"):
        EventSlam(cfg, rec.calibration, None)
    with pytest.raises(InputError, match="calibration"):
        run_slam(Recording(events=rec.events), SlamConfig())


def test_each_mode_warps_its_mcis_to_its_own_reference_fraction():
    rec = make_recording(duration_s=0.05)
    cfg = SlamConfig()
    cfg.mci.reference_fraction, cfg.mci.reference_fraction_inertial = 0.5, 0.8
    assert EventSlam(cfg, rec.calibration).mci_gen.cfg.reference_fraction == 0.5
    cfg.mode = SlamMode.EVENT_INERTIAL
    assert EventSlam(cfg, rec.calibration, rec.imu).mci_gen.cfg.reference_fraction == 0.8
    assert cfg.mci.reference_fraction == 0.5  # the caller's config is not changed


def test_event_only_mcis_default_to_the_middle_of_their_window_and_event_inertial_ones_to_its_end():
    rec = make_recording(duration_s=0.05)
    assert EventSlam(SlamConfig(), rec.calibration).mci_gen.cfg.reference_fraction == 0.5
    assert EventSlam(SlamConfig(mode=SlamMode.EVENT_INERTIAL), rec.calibration, rec.imu).mci_gen.cfg.reference_fraction == 1.0


def test_snapshot_and_restore_replay_identically():
    rec = make_recording(duration_s=1.0, speed=1.5, seed=9)
    slam = EventSlam(SlamConfig(), rec.calibration)
    ev = rec.events
    half = len(ev) // 2
    for a in range(0, half, 20000):
        slam.step(ev[a:min(a + 20000, half)])
    snap = slam.snapshot()
    n_before = len(slam.results)

    def finish():
        for a in range(half, len(ev), 20000):
            slam.step(ev[a:a + 20000])
        return [t for t in slam.atlas.trajectories()]

    first = finish()
    slam.restore(snap)
    assert len(slam.results) == n_before
    second = finish()
    assert len(first) == len(second) >= 1
    for x, y in zip(first, second):
        assert np.array_equal(x.t, y.t) and np.array_equal(x.position, y.position)


def test_support_gate_drops_tracks_on_empty_patches_only_while_a_map_is_tracked(radtan_recording, radtan_run):
    # A floor no patch can meet: every track is dropped as soon as the map is tracked, so it is lost, but the two-view
    # initialisation (not gated) still succeeds.
    cfg = SlamConfig()
    cfg.features.klt_min_support_ratio = 20.0
    gated = run_slam(radtan_recording, cfg)
    ok = lambda run: sum(r.status is SlamStatus.OK for r in run.results)
    assert 0 < ok(gated) < ok(radtan_run)
    assert any(r.status is SlamStatus.OK and "initialised" in r.reason for r in gated.results)


@pytest.fixture(scope="module")
def radtan_sensor_grid_run(radtan_recording):
    cfg = SlamConfig()
    cfg.features.klt_upsample = 1.0
    return run_slam(radtan_recording, cfg)


@pytest.mark.parametrize("refine", [False, True])
def test_fine_grid_klt_tracks_the_recording_and_changes_the_tracks(radtan_recording, radtan_sensor_grid_run, refine):
    cfg = SlamConfig()
    cfg.features.klt_upsample = 2.0
    cfg.features.klt_upsample_min_events_per_px = 0.0  # every MCI on the fine grid
    cfg.features.klt_upsample_refine = refine
    run = run_slam(radtan_recording, cfg)
    m = atlas_metrics(run.trajectories(), radtan_recording.ground_truth, correct_scale=True, duration_s=run.duration_s)
    assert len(m.maps) == 1 and m.tracked_fraction >= 0.8 and m.ate_percent <= 2.0
    # Track positions stay in sensor pixels, but differ from the sensor-grid KLT's.
    r = run.results[-1]
    assert r.features.shape[1] == 2 and r.features.max(axis=0)[0] < 240 and r.features.max(axis=0)[1] < 180
    assert not all(np.array_equal(a.features, b.features) for a, b in zip(run.results, radtan_sensor_grid_run.results))


def test_fine_grid_waits_for_the_warm_up_and_stays_off_on_sparse_recordings(radtan_recording, radtan_run, radtan_sensor_grid_run):
    # The synthetic recording holds over 1 event per pixel per MCI: the default warm-up lets the fine grid on, so the
    # tracks match the sensor-grid run's through the warm-up and differ after it.
    n = SlamConfig().features.klt_upsample_warmup_mcis
    same = [np.array_equal(a.features, b.features) for a, b in zip(radtan_run.results, radtan_sensor_grid_run.results)]
    assert all(same[:n]) and not all(same[n:])
    # A floor above the recording's density keeps it on the sensor grid throughout: the run is the sensor-grid run.
    cfg = SlamConfig()
    cfg.features.klt_upsample_min_events_per_px = 100.0
    sparse = run_slam(radtan_recording, cfg)
    assert len(sparse.results) == len(radtan_sensor_grid_run.results)
    assert all(np.array_equal(a.features, b.features) and np.array_equal(a.pose, b.pose)
               for a, b in zip(sparse.results, radtan_sensor_grid_run.results))
