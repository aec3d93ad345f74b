"""The re-acquisition search: after an event gap without ground truth the tracker searches for the pose instead of
restarting from the last estimate, finds a camera that moved on, refuses a scene that is not the map's, leaves runs
without a search bit for bit as they were, and does bounded work per update."""

import dataclasses

import numpy as np
import pytest
from tracker_synthetic import generate

from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.event_gaps import RestartGateConfig
from evpose.tracker.reacquisition import ReacquisitionConfig, hypotheses
from evpose.tracker.session import TrackingSession
from evpose.tracker.step_result import TrackStatus
from evpose.tracker.tracker import Tracker

HOUR_US = 3_600_000_000


def _config(enabled: bool = True, **search) -> TrackerConfig:
    cfg = TrackerConfig(mode=TrackerMode.STPE)
    cfg.reacquisition = dataclasses.replace(ReacquisitionConfig(enabled=enabled), **search)
    cfg.restart_gate = RestartGateConfig(min_chance_z=0.0)  # "off" is the restart from the last estimate, ungated
    return cfg


def _cut(rec, a_us: int, b_us: int, gap_us: int):
    """The recording with the flight between ``a_us`` and ``b_us`` cut out and a ``gap_us`` pause in its place: the
    camera moved on meanwhile."""
    def splice(t):
        keep = (t < a_us) | (t >= b_us)
        t = t[keep].copy()
        t[t >= b_us] += gap_us - (b_us - a_us)
        return keep, t
    ev, gt = rec.events, rec.ground_truth
    k, t = splice(ev.t)
    kg, tg = splice(gt.t)
    return dataclasses.replace(rec, events=EventArray(t, ev.x[k], ev.y[k], ev.p[k]),
                               ground_truth=Trajectory(tg, gt.position[kg], gt.quat_xyzw[kg]))


def _session(rec, cmap, cfg, t0_us):
    """A session started from an explicit pose (as ``evpose track --init``): no ground truth at the restart."""
    return TrackingSession(rec, cmap, cfg, initial_pose=rec.ground_truth.interpolate(t0_us).matrix(0), t_start_us=t0_us)


@pytest.fixture(scope="module")
def moved():
    """The box scene with 0.4 s of flight cut out after 0.15 s (the camera moved 0.12 m, 0.09 m of it in depth) and an
    hour's pause in its place; the truth after the gap is the original's."""
    rec, cmap, _ = generate(duration_s=1.0, seed=2)
    a, b = rec.t_start_us + 150_000, rec.t_start_us + 550_000
    return _cut(rec, a, b, HOUR_US), cmap, rec.ground_truth, a, b


def _after_gap(results):
    g = next(k for k, r in enumerate(results) if r.status is TrackStatus.LOST)
    return results[g], results[g + 1:]


def _errors(results, truth, a, b):
    t = np.array([r.t_us for r in results])
    t = np.where(t >= a + HOUR_US, t - HOUR_US + (b - a), t)
    return np.linalg.norm(np.array([r.pose[:3, 3] for r in results]) - truth.interpolate(t).position, axis=1)


def test_a_camera_that_moved_on_during_a_gap_is_found_again(moved):
    rec, cmap, truth, a, b = moved
    before = _session(rec, cmap, _config(enabled=False), rec.t_start_us).run()
    _, post = _after_gap(before)
    # Without the search: tracked from the last estimate, written as tracked, 0.1 m off to the end.
    assert all(r.status is not TrackStatus.LOST for r in post)
    assert np.min(_errors(post, truth, a, b)) > 0.05
    s = _session(rec, cmap, _config(), rec.t_start_us)
    gap, post = _after_gap(s.run())
    assert "searching for the pose" in gap.reason
    lost = [r for r in post if r.status is TrackStatus.LOST]
    assert 0 < len(lost) < 20 and all("re-acquisition" in r.reason for r in lost)
    found = next(k for k, r in enumerate(post) if r.status is not TrackStatus.LOST)
    assert post[found].counts.get("reacquired") == 1 and list(s.restarts) == [post[found].t_us]
    assert all(r.status is not TrackStatus.LOST for r in post[found:])
    assert np.max(_errors(post[-40:], truth, a, b)) < 0.015


def test_a_scene_that_is_not_the_map_is_never_accepted():
    """After the gap the camera sees the box scene mirrored: without the search the tracker locks onto it and writes
    every pose as tracked; with it every update is lost, naming the search."""
    rec, cmap, _ = generate(duration_s=0.5, seed=2)
    a = rec.t_start_us + 150_000
    ev, gt = rec.events, rec.ground_truth
    after = ev.t >= a
    x = np.where(after, rec.calibration.width - 1 - ev.x, ev.x).astype(ev.x.dtype)
    y = np.where(after, rec.calibration.height - 1 - ev.y, ev.y).astype(ev.y.dtype)
    mirrored = dataclasses.replace(rec, events=EventArray(np.where(after, ev.t + HOUR_US, ev.t), x, y, ev.p),
                                   ground_truth=Trajectory(np.where(gt.t >= a, gt.t + HOUR_US, gt.t), gt.position, gt.quat_xyzw))
    _, post = _after_gap(_session(mirrored, cmap, _config(enabled=False), rec.t_start_us).run())
    assert sum(r.status is TrackStatus.OK for r in post) > 0.9 * len(post)  # the wrong lock the search is for
    _, post = _after_gap(_session(mirrored, cmap, _config(), rec.t_start_us).run())
    assert len(post) > 40 and all(r.status is TrackStatus.LOST and "re-acquisition" in r.reason for r in post)


def test_the_search_is_off_by_default_and_the_restart_is_from_the_last_estimate(moved):
    rec, cmap, _, _, _ = moved
    assert TrackerConfig().reacquisition.enabled is False
    gap, post = _after_gap(_session(rec, cmap, TrackerConfig(mode=TrackerMode.STPE), rec.t_start_us).run())
    assert "restarted after it from the last estimate" in gap.reason and not any("re-acquisition" in r.reason for r in post)


def test_a_run_without_a_search_is_bit_identical(moved):
    rec, cmap, _, a, _ = moved
    short = dataclasses.replace(rec, events=rec.events.time_window(rec.t_start_us, a))
    on = _session(short, cmap, _config(), rec.t_start_us).run()
    off = _session(short, cmap, _config(enabled=False), rec.t_start_us).run()
    assert len(on) == len(off) > 20
    assert all(np.array_equal(p.pose, q.pose) and p.status is q.status for p, q in zip(on, off))
    # From ground truth the restart after a gap needs no search either.
    gt_on = TrackingSession(rec, cmap, _config()).run()
    gt_off = TrackingSession(rec, cmap, _config(enabled=False)).run()
    assert all(np.array_equal(p.pose, q.pose) and p.reason == q.reason for p, q in zip(gt_on, gt_off))


def test_the_work_per_search_update_is_bounded(moved, monkeypatch):
    rec, cmap, _, _, _ = moved
    cfg = _config(max_hypotheses=9, keep_trials=3, prune_after=2)
    calls = []
    track = Tracker.track

    def counted(self, *args, **kwargs):
        calls.append(1)
        return track(self, *args, **kwargs)

    monkeypatch.setattr(Tracker, "track", counted)
    s = _session(rec, cmap, cfg, rec.t_start_us)
    per_update = []
    while not s.done:
        calls.clear()
        r = s.step()
        if "re-acquisition" in r.reason or r.counts.get("reacquired"):
            per_update.append(len(calls))
    # The gap's update only sets the trials up; then at most 9 tracker updates, and after pruning at most the 3 best
    # trials and the centre's.
    assert per_update[0] == 0 and max(per_update) == 9 and per_update[1] == 9
    assert set(per_update[1:]) <= {1, 2, 3, 4, 9}


def test_the_grid_grows_with_the_elapsed_time_up_to_its_radius():
    cfg = ReacquisitionConfig(speed_m_s=1.0, max_radius_m=0.5, grid_step_px=10.0, max_hypotheses=1000)
    step = 10.0 * 2.0 / 200.0  # 0.1 m at 2 m depth, f 200 px
    sizes = [len(hypotheses(cfg, np.eye(4), 2.0, 200.0, s)) for s in (0.0, 0.2, 0.35, 10.0)]
    assert sizes == [5, 13, 29, 81]  # radius one step at least, then 0.2 / 0.3 / 0.5 m
    g = hypotheses(cfg, np.eye(4), 2.0, 200.0, 10.0)
    assert np.allclose(g[0], np.eye(4)) and np.all(np.linalg.norm(g[:, :3, 3], axis=1) <= 0.5 + 1e-9)
    assert np.allclose(g[:, 2, 3], 0.0) and np.allclose(np.abs(g[1:5, :2, 3]).sum(axis=1), step)
    capped = hypotheses(dataclasses.replace(cfg, max_hypotheses=7), np.eye(4), 2.0, 200.0, 10.0)
    assert np.array_equal(capped, g[:7])


def test_seeking_back_into_a_search_replays_it_bit_for_bit(moved):
    rec, cmap, _, _, _ = moved
    cfg = _config(max_hypotheses=9)
    cfg.snapshot_every = 5
    ref = _session(rec, cmap, cfg, rec.t_start_us).run()
    k = next(i for i, r in enumerate(ref) if "re-acquisition round" in r.reason) + 3
    s = _session(rec, cmap, dataclasses.replace(cfg), rec.t_start_us)
    s.seek(ref[-1].t_us)
    for j in (k, k + 6, len(ref) - 1):
        r = s.seek(ref[j].t_us)
        assert np.array_equal(r.pose, ref[j].pose) and r.reason == ref[j].reason
