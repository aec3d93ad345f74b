"""Running SLAM over a whole recording: events fed in fixed slices, everything the run produced."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.eval.slam_metrics import status_durations_s
from evpose.slam.atlas import Atlas
from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.step_result import SlamStatus, SlamStepResult
from evpose.slam.system import EventSlam


@dataclass
class SlamRun:
    """Everything a run produced."""

    results: list[SlamStepResult]
    """One per processed MCI."""
    atlas: Atlas
    duration_s: float
    """Span of the recording's events, seconds."""
    wall_s: float
    """Wall time of the run, seconds."""
    start_us: int = 0
    """Time of the recording's first event, us."""

    def trajectories(self) -> list[Trajectory]:
        return self.atlas.trajectories()

    def time_by_status_s(self) -> dict[str, float]:
        """Seconds of the recording under each step status (see :func:`evpose.eval.slam_metrics.status_durations_s`)."""
        end_us = self.start_us + int(round(self.duration_s * 1e6))
        return status_durations_s(np.array([r.t_us for r in self.results], np.int64), [r.status.value for r in self.results],
                                  self.start_us, end_us)

    def time_by_failure_s(self) -> dict[str, float]:
        """Seconds of the recording not tracked from the events, by why: each MCI not tracked from the events owns the
        span :meth:`time_by_status_s` credits it with; the part of that span the window selection dropped for a low
        event rate (``counts["blank_us"]``) goes to ``"blank"``, the rest to the MCI's :class:`~evpose.slam.step_result.SlamFailure` value."""
        out: dict[str, float] = {}
        prev = self.start_us
        for r in self.results:
            span = max(r.t_us - prev, 0)
            prev = max(prev, r.t_us)
            if r.status is SlamStatus.OK:
                continue
            blank = min(int(r.counts.get("blank_us", 0)), span)
            for key, us in (("blank", blank), (r.failure.value or "other", span - blank)):
                if us > 0:
                    out[key] = out.get(key, 0.0) + us / 1e6
        return dict(sorted(out.items()))

    @property
    def visual_fraction(self) -> float:
        """Share of the recording tracked from the events (status ``ok``): coasted and IMU-bridged time left out."""
        return self.time_by_status_s().get(SlamStatus.OK.value, 0.0) / self.duration_s if self.duration_s > 0 else 0.0


def run_slam(recording: Recording, config: SlamConfig, chunk_us: int = 5000, slam: EventSlam | None = None) -> SlamRun:
    """Run SLAM over a whole recording, feeding events in ``chunk_us`` slices."""
    if recording.calibration is None:
        raise InputError(recording.source, "the recording has no camera calibration; SLAM needs one")
    if config.mode is SlamMode.EVENT_INERTIAL and slam is None:
        imu, ev = recording.imu, recording.events
        if imu is None or len(imu) < 2:
            raise InputError(recording.source, "event-inertial mode needs at least 2 IMU samples; the recording has " + ("none" if imu is None else str(len(imu))), "imu")
        t0 = int(ev.t[0]) + recording.calibration.time_offset_us if len(ev) else None
        if t0 is not None and not imu.covers(t0, t0 + 1):
            raise InputError(recording.source, f"the IMU samples ({int(imu.t[0])}..{int(imu.t[-1])} us, IMU clock) do not cover "
                             f"the first event at {t0} us: is the IMU on another clock?", "imu")
    slam = slam or EventSlam(config, recording.calibration, recording.imu)
    ev = recording.events
    t_start = time.perf_counter()
    if len(ev):
        t0, t1 = int(ev.t[0]), int(ev.t[-1])
        edges = np.arange(t0, t1 + chunk_us, chunk_us, dtype=np.int64)
        idx = np.searchsorted(ev.t, edges, side="left")
        idx[-1] = len(ev)
        for a, b in zip(idx[:-1], idx[1:]):
            if b > a:
                slam.step(ev[a:b])
        slam.finish()  # the events after the last reconstruction window (EventWindowConfig.flush_min_fraction)
    return SlamRun(slam.results, slam.atlas, ev.duration_us / 1e6, time.perf_counter() - t_start, int(ev.t[0]) if len(ev) else 0)
