"""TrackingSession: stepping over a recording, seeking equals an uninterrupted run, bad-input errors."""

import dataclasses

import numpy as np
import pytest
from tracker_synthetic import generate

from evpose.errors import InputError
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.session import TrackingSession
from evpose.tracker.step_result import TrackStatus

# The synthetic scene has no IMU; these tests are about the STPE engine itself.
STPE = TrackerConfig(mode=TrackerMode.STPE)


@pytest.fixture(scope="module")
def scene():
    rec, cmap, _ = generate(duration_s=0.2, seed=2)
    return rec, cmap


def test_session_steps_to_the_end_and_builds_a_trajectory(scene):
    rec, cmap = scene
    s = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.STPE, rate_hz=200.0))
    results = s.run()
    assert s.step() is None and s.done
    assert len(results) == s.total_steps == (rec.t_end_us - s.t0_us) // 5_000
    assert [r.t_us for r in results] == [s.t0_us + 5_000 * (k + 1) for k in range(len(results))]
    traj = s.trajectory()
    assert len(traj) == sum(r.status is TrackStatus.OK for r in results) > 0.9 * len(results)


def test_seek_back_and_forward_equals_an_uninterrupted_run(scene):
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE, snapshot_every=7)
    straight = TrackingSession(rec, cmap, cfg)
    ref = straight.run()
    s = TrackingSession(rec, cmap, dataclasses.replace(cfg))
    for _ in range(30):
        s.step()
    for k in (12, 3, 25, 0, len(ref) - 1):
        r = s.seek(ref[k].t_us)
        assert r.t_us == ref[k].t_us and len(s.results) == k + 1
        assert np.array_equal(r.pose, ref[k].pose) and r.counts == ref[k].counts
    s.run()
    assert all(np.array_equal(a.pose, b.pose) for a, b in zip(s.results, ref))


def test_session_without_ground_truth_needs_an_initial_pose(scene):
    rec, cmap = scene
    bare = dataclasses.replace(rec, ground_truth=None)
    with pytest.raises(InputError, match="initial pose"):
        TrackingSession(bare, cmap, STPE)
    s = TrackingSession(bare, cmap, STPE, initial_pose=rec.ground_truth.matrix(0), t_start_us=int(rec.ground_truth.t[0]))
    assert s.step().status is TrackStatus.OK


def test_session_without_calibration_is_an_input_error(scene):
    rec, cmap = scene
    with pytest.raises(InputError, match="calibration"):
        TrackingSession(dataclasses.replace(rec, calibration=None), cmap, STPE)


def test_map_in_another_frame_is_an_input_error(scene):
    rec, cmap = scene
    moved = dataclasses.replace(cmap, points=cmap.points + np.array([100.0, 0.0, 0.0]))
    with pytest.raises(InputError, match="same frame"):
        TrackingSession(rec, moved, STPE)


def test_forward_seek_over_known_results_jumps_by_snapshot_and_equals_an_uninterrupted_run(scene):
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE, snapshot_every=5)
    ref = TrackingSession(rec, cmap, cfg).run()
    s = TrackingSession(rec, cmap, dataclasses.replace(cfg))
    s.run()
    s.seek(ref[2].t_us)
    calls = []
    step = s.tracker.step
    s.tracker.step = lambda *a, **k: calls.append(1) or step(*a, **k)
    r = s.seek(ref[-2].t_us)
    # At most one snapshot interval is replayed, not the whole way from step 3.
    assert len(calls) < cfg.snapshot_every and len(s.results) == len(ref) - 1
    assert np.array_equal(r.pose, ref[-2].pose)
    assert all(np.array_equal(a.pose, b.pose) and a.t_us == b.t_us for a, b in zip(s.results, ref))
    s.run()
    assert len(s.results) == len(ref) and all(np.array_equal(a.pose, b.pose) for a, b in zip(s.results, ref))


def test_a_snapshot_handed_to_another_session_replays_the_same_steps(scene):
    rec, cmap = scene
    a, b = TrackingSession(rec, cmap, STPE), TrackingSession(rec, cmap, STPE)
    for _ in range(6):
        a.step()
    step = a.take_snapshot()
    b.adopt_snapshot(step, a.snapshot_at(step))
    b.restore_snapshot(step)
    for _ in range(4):
        ra, rb = a.step(), b.step()
        assert np.array_equal(ra.pose, rb.pose) and ra.status is rb.status


def test_a_session_run_straight_through_keeps_only_the_start_snapshot_and_still_seeks(scene):
    rec, cmap = scene
    cfg = TrackerConfig(mode=TrackerMode.STPE, snapshot_every=5)
    ref = TrackingSession(rec, cmap, cfg).run()
    s = TrackingSession(rec, cmap, dataclasses.replace(cfg), seekable=False)
    out = s.run()
    assert s.snapshot_steps == [0]  # not one per 5 updates: memory grew with the recording's length
    assert all(np.array_equal(a.pose, b.pose) for a, b in zip(out, ref)) and len(out) == len(ref)
    r = s.seek(ref[10].t_us)  # replayed from the start
    assert np.array_equal(r.pose, ref[10].pose)
