"""A long pause of the input (events, or in event-inertial mode IMU samples) ends the active map: one LOST step result
stands for it, nothing is propagated across it, and a new map starts after it."""

import numpy as np
import pytest

from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.slam import SlamConfig, SlamMode, SlamStatus, run_slam
from evpose.slam.step_result import SlamFailure
from slam_synthetic import make_recording

PAUSE_US, CUT_US = 60_000_000, 1_200_000


@pytest.fixture(scope="module")
def flight():
    return make_recording(duration_s=2.4, speed=1.5, seed=7, shake=0.08)


def _later(t: np.ndarray) -> np.ndarray:
    t = t.copy()
    t[t >= CUT_US] += PAUSE_US
    return t


@pytest.fixture(scope="module")
def paused(flight):
    """The recorder paused for 60 s at 1.2 s: events, IMU and ground truth after it moved later."""
    ev, imu, gt = flight.events, flight.imu, flight.ground_truth
    return Recording(events=EventArray(_later(ev.t), ev.x, ev.y, ev.p), imu=ImuSamples(_later(imu.t), imu.acc, imu.gyro),
                     ground_truth=Trajectory(_later(gt.t), gt.position, gt.quat_xyzw), calibration=flight.calibration)


def _gap_results(run):
    return [r for r in run.results if r.failure is SlamFailure.GAP]


@pytest.mark.parametrize("mode", [SlamMode.EVENT, SlamMode.EVENT_INERTIAL])
def test_a_pause_ends_the_map_and_a_new_one_starts_after_it(paused, mode):
    run = run_slam(paused, SlamConfig(mode=mode))
    gaps = _gap_results(run)
    assert len(gaps) == 1 and gaps[0].status is SlamStatus.LOST and "60.0" in gaps[0].reason
    assert gaps[0].t_us == int(paused.events.t[paused.events.t >= CUT_US + PAUSE_US][0])
    maps = [m for m in run.atlas.maps if m.traj_t]
    assert len(maps) == 2 and maps[0].lost_reason.startswith("no ")
    assert max(maps[0].traj_t) < CUT_US and min(maps[1].traj_t) > CUT_US + PAUSE_US
    # The pause is not tracked time, and no pose was made up inside it.
    assert run.time_by_status_s()["lost"] >= PAUSE_US / 1e6 and run.time_by_status_s()["ok"] < 2.4
    assert run.time_by_failure_s()["gap"] >= PAUSE_US / 1e6


def test_no_map_ends_at_a_pause_with_the_limit_off(paused):
    cfg = SlamConfig()
    cfg.tracking.lose_after_gap_s = 0.0
    assert not _gap_results(run_slam(paused, cfg))


def test_event_inertial_uses_no_events_inside_an_imu_hole(flight):
    imu = flight.imu
    keep = (imu.t < 800_000) | (imu.t > 1_950_000)
    rec = Recording(events=flight.events, imu=ImuSamples(imu.t[keep], imu.acc[keep], imu.gyro[keep]),
                    ground_truth=flight.ground_truth, calibration=flight.calibration)
    run = run_slam(rec, SlamConfig(mode=SlamMode.EVENT_INERTIAL))
    gaps = _gap_results(run)
    assert len(gaps) == 1 and "no IMU samples for 1.1" in gaps[0].reason
    t = np.concatenate([m.traj_t for m in run.atlas.maps if m.traj_t])
    assert not np.any((t > 800_000) & (t < 1_950_000))


def test_event_inertial_says_once_where_the_imu_ends(flight):
    imu = flight.imu
    keep = imu.t <= 1_000_000
    rec = Recording(events=flight.events, imu=ImuSamples(imu.t[keep], imu.acc[keep], imu.gyro[keep]),
                    ground_truth=flight.ground_truth, calibration=flight.calibration)
    run = run_slam(rec, SlamConfig(mode=SlamMode.EVENT_INERTIAL))
    gaps = _gap_results(run)
    assert len(gaps) == 1 and "IMU samples end at t=1.000000 s" in gaps[0].reason
    # Sample-and-hold bridges the IMU up to lose_after_gap_s past its end, as it bridges shorter holes.
    assert max(max(m.traj_t) for m in run.atlas.maps if m.traj_t) <= 2_000_000
