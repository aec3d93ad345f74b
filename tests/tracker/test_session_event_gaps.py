"""TrackingSession over a recording whose events pause for an hour: one lost update for the gap, then tracking again."""

import dataclasses

import numpy as np
import pytest
from tracker_synthetic import generate

from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.session import TrackingSession
from evpose.tracker.step_result import TrackStatus

HOUR_US = 3_600_000_000


def with_gap(rec, at_us: int, gap_us: int):
    """The recording with everything from ``at_us`` on moved ``gap_us`` later (a recorder paused that long)."""
    def shift(t):
        return np.where(t >= at_us, t + gap_us, t)
    ev, gt = rec.events, rec.ground_truth
    return dataclasses.replace(rec, events=EventArray(shift(ev.t), ev.x, ev.y, ev.p),
                               ground_truth=Trajectory(shift(gt.t), gt.position, gt.quat_xyzw))


@pytest.fixture(scope="module")
def paused():
    rec, cmap, _ = generate(duration_s=0.3, seed=2)
    return with_gap(rec, rec.t_start_us + 150_000, HOUR_US), cmap


def test_an_hour_without_events_is_one_lost_update_and_tracking_resumes_after_it(paused):
    rec, cmap = paused
    s = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.STPE))
    results = s.run()
    assert s.total_steps == len(results) < 70  # not 720 000 updates
    lost = [r for r in results if r.status is TrackStatus.LOST]
    assert len(lost) == 1 and "no events for 3600.0" in lost[0].reason and "ground-truth pose" in lost[0].reason
    after = [r for r in results if r.t_us > lost[0].t_us]
    assert len(after) > 15 and all(r.status is TrackStatus.OK for r in after)
    gt = rec.ground_truth.interpolate(np.array([r.t_us for r in after]))
    assert np.max(np.linalg.norm(np.array([r.pose[:3, 3] for r in after]) - gt.position, axis=1)) < 0.03
    assert list(s.restarts) == [lost[0].t_us]


def test_seeking_across_an_event_gap_equals_an_uninterrupted_run(paused):
    rec, cmap = paused
    cfg = TrackerConfig(mode=TrackerMode.STPE, snapshot_every=7)
    ref = TrackingSession(rec, cmap, cfg).run()
    s = TrackingSession(rec, cmap, dataclasses.replace(cfg))
    gap_k = next(k for k, r in enumerate(ref) if r.status is TrackStatus.LOST)
    for k in (len(ref) - 1, gap_k - 1, gap_k, gap_k + 3, 2):
        r = s.seek(ref[k].t_us)
        assert r.t_us == ref[k].t_us and len(s.results) == k + 1 and np.array_equal(r.pose, ref[k].pose)
    # a time inside the gap lands on the last update before it
    assert s.seek(ref[gap_k - 1].t_us + HOUR_US // 2).t_us == ref[gap_k - 1].t_us
    assert s.steps_until(ref[gap_k].t_us) == gap_k + 1


def test_an_event_gap_shorter_than_the_limit_is_stepped_through(paused):
    rec, cmap = paused
    short = with_gap(generate(duration_s=0.3, seed=2)[0], rec.t_start_us + 150_000, 200_000)
    s = TrackingSession(short, cmap, TrackerConfig(mode=TrackerMode.STPE))
    assert s.total_steps == (s.t_end_us - s.t0_us) // s.dt_us and s.schedule.gaps == []
