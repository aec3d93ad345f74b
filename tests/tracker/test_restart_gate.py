"""The chance-level gate on a restart from the last estimate (``restart_gate``): it withholds a wrong lock after an
event gap (the scene after it is the map's mirrored), lets a right restart through after ``run_updates`` with the
ungated poses, gives a restart up after its deadline, survives seeking, and leaves runs from ground truth as they were."""

import dataclasses

import numpy as np
import pytest
from tracker_synthetic import generate

from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.event_gaps import RestartGateConfig
from evpose.tracker.session import TrackingSession
from evpose.tracker.step_result import TrackStatus

HOUR_US = 3_600_000_000


def _config(min_chance_z: float, run_updates: int = 10, deadline_updates: int = 0, **kw) -> TrackerConfig:
    gate = RestartGateConfig(min_chance_z=min_chance_z, run_updates=run_updates, deadline_updates=deadline_updates)
    return TrackerConfig(mode=TrackerMode.STPE, restart_gate=gate, **kw)


def _paused(rec, at_us: int, mirror: bool = False):
    """``rec`` with everything from ``at_us`` on an hour later (the camera did not move meanwhile); ``mirror``: the
    events after the pause mirrored in both image axes (a scene that is not the map's)."""
    ev, gt = rec.events, rec.ground_truth
    after = ev.t >= at_us
    x, y = ev.x, ev.y
    if mirror:
        x = np.where(after, rec.calibration.width - 1 - ev.x, ev.x).astype(ev.x.dtype)
        y = np.where(after, rec.calibration.height - 1 - ev.y, ev.y).astype(ev.y.dtype)
    return dataclasses.replace(rec, events=EventArray(np.where(after, ev.t + HOUR_US, ev.t), x, y, ev.p),
                               ground_truth=Trajectory(np.where(gt.t >= at_us, gt.t + HOUR_US, gt.t), gt.position, gt.quat_xyzw))


def _from_init(rec, cmap, cfg):
    """As ``evpose track --init``: no ground truth at the restart."""
    return TrackingSession(rec, cmap, cfg, initial_pose=rec.ground_truth.interpolate(rec.t_start_us).matrix(0),
                           t_start_us=rec.t_start_us)


def _after_gap(results):
    g = next(k for k, r in enumerate(results) if "no events for" in r.reason)
    return results[:g + 1], results[g + 1:]


@pytest.fixture(scope="module")
def box():
    rec, cmap, _ = generate(duration_s=0.5, seed=2)
    return rec, cmap, rec.t_start_us + 150_000


def test_the_gate_withholds_a_lock_onto_a_scene_that_is_not_the_map(box):
    rec, cmap, at = box
    mirrored = _paused(rec, at, mirror=True)
    _, post = _after_gap(_from_init(mirrored, cmap, _config(0.0)).run())
    assert sum(r.status is TrackStatus.OK for r in post) > 0.9 * len(post)  # ungated: the wrong lock is written
    # Its median chance-level z stays at 6-10 (the right restart below: ~45).
    _, post = _after_gap(_from_init(mirrored, cmap, _config(16.0)).run())
    assert len(post) > 40 and all(r.status is TrackStatus.LOST and "not acquired again" in r.reason for r in post)


def test_a_right_restart_passes_after_run_updates_with_the_ungated_poses(box):
    rec, cmap, at = box
    paused = _paused(rec, at)
    before0, post0 = _after_gap(_from_init(paused, cmap, _config(0.0)).run())
    before, post = _after_gap(_from_init(paused, cmap, _config(16.0, run_updates=5)).run())
    assert all(np.array_equal(p.pose, q.pose) and p.status is q.status for p, q in zip(before, before0))
    assert [r.status for r in post[:4]] == [TrackStatus.LOST] * 4
    assert all(r.status is TrackStatus.OK for r in post0) and all(r.status is TrackStatus.OK for r in post[4:])
    assert all(np.array_equal(p.pose, q.pose) for p, q in zip(post, post0))


def test_seeking_back_into_a_gated_stretch_replays_it(box):
    rec, cmap, at = box
    cfg = _config(16.0, run_updates=5, snapshot_every=3)
    ref = _from_init(_paused(rec, at), cmap, cfg).run()
    s = _from_init(_paused(rec, at), cmap, cfg)
    g = next(k for k, r in enumerate(ref) if "no events for" in r.reason)
    for k in (len(ref) - 1, g + 2, g + 6, g + 1):
        r = s.seek(ref[k].t_us)
        assert r.status is ref[k].status and r.reason == ref[k].reason and np.array_equal(r.pose, ref[k].pose)


def test_the_gate_is_on_by_default_and_never_judges_a_restart_from_ground_truth(box):
    rec, cmap, at = box
    assert TrackerConfig().restart_gate.min_chance_z > 0 and TrackerConfig().restart_gate.deadline_updates > 0
    paused = _paused(rec, at)
    on = TrackingSession(paused, cmap, _config(1e9)).run()
    off = TrackingSession(paused, cmap, _config(0.0)).run()
    assert len(on) == len(off) and all(np.array_equal(p.pose, q.pose) and p.reason == q.reason for p, q in zip(on, off))


def test_a_restart_not_acquired_within_the_deadline_is_given_up(box):
    rec, cmap, at = box
    paused = _paused(rec, at)
    # The right restart passes after 5 updates: a deadline of 3 gives it up for good, one of 5 lets it through.
    _, post = _after_gap(_from_init(paused, cmap, _config(16.0, run_updates=5, deadline_updates=3)).run())
    assert all(r.status is TrackStatus.LOST for r in post)
    assert all("within 3 updates: nothing is written until the next restart" in r.reason for r in post[3:])
    _, post = _after_gap(_from_init(paused, cmap, _config(16.0, run_updates=5, deadline_updates=5)).run())
    assert post[4].status is TrackStatus.OK
