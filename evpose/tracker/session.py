"""TrackingSession: drives a :class:`Tracker` over a :class:`Recording` one update at a time, with seeking.

The session owns the cursors into the recording (event index, step index),
keeps a full-state snapshot every ``config.snapshot_every`` steps, and can
``seek`` to any time by restoring the nearest earlier snapshot and replaying;
the replayed state equals an uninterrupted run because every stage is
deterministic. This is the object the CLI, the benchmarks and the viewer use.
"""

from __future__ import annotations

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.tracker.config import TrackerConfig, TrackerMode
from evpose.tracker.modes import build_motion_components
from evpose.tracker.step_result import StepResult, TrackStatus
from evpose.tracker.tracker import MotionPredictor, PolaritySelector, Tracker



class MapOutOfViewError(InputError):
    """Too few map points are in view at the initial pose: most often a map of another scene or frame (the fault
    is then the map's, though the recording is what the session knows)."""

class TrackingSession:
    """One tracking run over a recording: ``step()`` until it returns None; ``seek(t)`` to go back or forward."""

    def __init__(
        self,
        recording: Recording,
        contour_map: ContourMap,
        config: TrackerConfig | None = None,
        initial_pose: np.ndarray | None = None,
        t_start_us: int | None = None,
        predictor: MotionPredictor | None = None,
        polarity_selector: PolaritySelector | None = None,
    ):
        """``initial_pose`` None -> the ground-truth pose at the first time with ``warmup_ms`` of events before it
        (the first ground-truth pose when events precede it); else that pose at ``t_start_us`` (default: the first event)."""
        self.recording = recording
        self.config = config if config is not None else TrackerConfig()
        src = str(recording.source) if recording.source else None
        if recording.calibration is None:
            raise InputError(src, "the recording has no camera calibration; tracking needs intrinsics")
        events = recording.events
        if len(events) == 0:
            raise InputError(src, "the recording has no events")
        if self.config.rate_hz <= 0:
            raise InputError(None, f"rate_hz must be positive, got {self.config.rate_hz}")
        if initial_pose is None:
            gt = recording.ground_truth
            if gt is None or len(gt) == 0:
                raise InputError(src, "no initial pose given and the recording has no ground truth to start from")
            # Start where the front end has seen ``warmup_ms`` of events, so the first update has a field to register on.
            warm = int(round(self.config.warmup_ms * 1e3))
            t0 = max(int(gt.t[0]), int(events.t[0]) + warm) if t_start_us is None else int(t_start_us)
            if t0 > int(gt.t[-1]):
                raise InputError(src, "the ground truth ends before the first event; cannot start from it")
            pose0 = gt.interpolate(t0).matrix(0)
        else:
            pose0 = np.asarray(initial_pose, dtype=np.float64).reshape(4, 4)
            t0 = int(events.t[0]) if t_start_us is None else int(t_start_us)
        v0 = None
        seed_velocity = initial_pose is None and self.config.initial_velocity_from_ground_truth
        if seed_velocity:
            h = 5000  # central difference over +-5 ms of ground truth, microseconds
            p = gt.interpolate(np.array([max(t0 - h, int(gt.t[0])), min(t0 + h, int(gt.t[-1]))])).position
            v0 = (p[1] - p[0]) / (2 * h * 1e-6)
        components = None
        if predictor is None and polarity_selector is None:
            has_imu = recording.imu is not None and len(recording.imu) > 1
            components = build_motion_components(self.config, contour_map, recording.calibration, has_imu, v0, src)
        self.tracker = Tracker(self.config, contour_map, recording.calibration, predictor, polarity_selector, components)
        n_vis = self.tracker.start(pose0, t0)
        if components is not None and components.motion is not None:
            # IMU samples just before the start let the first preintegration interpolate at t0.
            off = recording.calibration.time_offset_us
            if recording.imu is not None and len(recording.imu) > 1 and not recording.imu.covers(t0 + off, t0 + off + 1):
                raise InputError(src, f"the IMU samples ({int(recording.imu.t[0])}..{int(recording.imu.t[-1])} us, IMU clock) do not "
                                 f"cover the start of tracking at {t0 + off} us: is the IMU on another clock?", "imu")
            components.motion.fusion.add_imu(recording.imu.time_window(t0 + off - 20_000, t0 + off))
        fused_pose = components is not None and components.drives_pose
        if seed_velocity and not fused_pose:
            # Starting "from ground truth" gives the motion model the true initial velocity too.
            t_prev = t0 - max(int(round(1e6 / float(self.config.rate_hz))), 1)
            if t_prev >= int(gt.t[0]):
                self.tracker.predictor.reset(t_prev, gt.interpolate(t_prev).matrix(0))
                self.tracker.predictor.update(t0, pose0)
        need = self.config.registration.min_points
        if n_vis < need:
            raise MapOutOfViewError(
                src,
                f"only {n_vis} map points are in view at the initial pose (need {need}): are the map and the recording in the same frame?",
            )
        self.t0_us = t0
        self.dt_us = max(int(round(1e6 / float(self.config.rate_hz))), 1)
        self.t_end_us = int(events.t[-1])
        # Warm-up: let the front end see the events just before the start.
        w0 = t0 - int(round(self.config.warmup_ms * 1e3))
        i0, i1 = events.index_range(w0, t0)
        if i1 > i0:
            self.tracker.feed(events[i0:i1])
        self._cursor = i1
        self._step_index = 0
        self.results: list[StepResult] = []
        """StepResults so far, one per update, in time order."""
        self._future: list[StepResult] = []
        # Results after ``results`` computed before a backward restore: they let forward seeks jump.
        self._snapshots: dict[int, tuple[dict, int]] = {}
        self._take_snapshot()

    # ------------------------------------------------------------------ state
    @property
    def t_us(self) -> int:
        """Time of the last update (the start time before the first)."""
        return self.t0_us + self._step_index * self.dt_us

    @property
    def step_count(self) -> int:
        return self._step_index

    @property
    def total_steps(self) -> int:
        """Number of updates a full run makes."""
        return max((self.t_end_us - self.t0_us) // self.dt_us, 0)

    @property
    def done(self) -> bool:
        return self._step_index >= self.total_steps

    def _take_snapshot(self) -> None:
        self._snapshots[self._step_index] = (self.tracker.snapshot(), self._cursor)

    # ------------------------------------------------------------- snapshots
    @property
    def snapshot_steps(self) -> list[int]:
        """Step counts at which a full-state snapshot is kept, ascending."""
        return sorted(self._snapshots)

    def take_snapshot(self) -> int:
        """Keep a snapshot of the current state (in addition to the regular grid); returns its step count."""
        self._take_snapshot()
        return self._step_index

    def drop_snapshot(self, step: int) -> None:
        """Forget the snapshot at ``step`` (the one at step 0 is always kept)."""
        if step != 0:
            self._snapshots.pop(int(step), None)

    def snapshot_at(self, step: int):
        """The snapshot kept at ``step`` (must be in :attr:`snapshot_steps`): an opaque object for
        :meth:`adopt_snapshot` of another session of the same recording, map and configuration."""
        return self._snapshots[int(step)]

    def adopt_snapshot(self, step: int, snapshot) -> None:
        """Keep ``snapshot`` (from :meth:`snapshot_at` of a session of the same recording, map and configuration)
        as this session's snapshot at ``step``. Restoring copies its state out, so both sessions may use it."""
        self._snapshots[int(step)] = snapshot

    def restore_snapshot(self, step: int) -> None:
        """Put the engine in the state of the snapshot at ``step`` (must be in :attr:`snapshot_steps`).

        ``results`` is cut to ``step`` entries where it is longer (the cut results are kept,
        and restored when a later call goes forward over them); a caller that restores past
        the results ever computed must extend ``results`` itself.
        """
        step = int(step)
        state, cursor = self._snapshots[step]
        aligned = len(self.results) == self._step_index
        if not aligned:
            self._future = []  # someone edited ``results``: what lies ahead is no longer known by index
        if step < len(self.results):
            # Keep the results cut off: a later forward seek may jump over them (every stage is deterministic).
            self._future = self.results[step:] + (self._future if aligned else [])
            del self.results[step:]
        elif step > len(self.results) and aligned:
            n = step - len(self.results)
            self.results.extend(self._future[:n])
            self._future = self._future[n:]
        self.tracker.restore(state)
        self._cursor = cursor
        self._step_index = step

    # ------------------------------------------------------------------- run
    def step(self, debug: bool = False) -> StepResult | None:
        """One update at the next grid time; None once the recording's events are exhausted."""
        if self.done:
            return None
        until = self.t_us + self.dt_us
        ev = self.recording.events
        i1 = int(np.searchsorted(ev.t, until, side="left"))
        batch = ev[self._cursor : i1]
        imu = None
        if self.recording.imu is not None:
            off = self.recording.calibration.time_offset_us
            imu = self.recording.imu.time_window(self.t_us + off, until + off)
        result = self.tracker.step(until, batch, imu=imu, debug=debug)
        self._cursor = i1
        self._step_index += 1
        self.results.append(result)
        if self._future:
            self._future.pop(0)  # the same result, computed again
        if self._step_index % int(self.config.snapshot_every) == 0:
            self._take_snapshot()
        return result

    def run(self, progress=None) -> list[StepResult]:
        """Step to the end; ``progress(result)`` is called after each update (e.g. a tqdm update)."""
        while (r := self.step()) is not None:
            if progress is not None:
                progress(r)
        return self.results

    def seek(self, t_us: int, debug: bool = False) -> StepResult | None:
        """Move to the last update at or before ``t_us`` (restore the nearest snapshot, replay); returns it.

        The state afterwards equals an uninterrupted run's; ``debug`` asks for the
        debug products of the update landed on.
        """
        target = int(np.clip((int(t_us) - self.t0_us) // self.dt_us, 0, self.total_steps))
        if target < self._step_index:
            self.restore_snapshot(max(k for k in self._snapshots if k <= target))
        elif len(self.results) == self._step_index:
            # Forward: jump to the last snapshot on the way whose results between are already known
            # (from before an earlier backward seek); replaying is what makes the others.
            known = len(self.results) + len(self._future)
            ahead = [k for k in self._snapshots if self._step_index < k <= min(target, known)]
            if ahead:
                self.restore_snapshot(max(ahead))
        last = self.results[-1] if self.results else None
        while self._step_index < target:
            last = self.step(debug=debug and self._step_index == target - 1)
        return last

    def trajectory(self, include_lost: bool = False) -> Trajectory:
        """Poses of the updates so far (only those with a trustworthy status unless ``include_lost``)."""
        good = (TrackStatus.OK, TrackStatus.DEGRADED)
        sel = [r for r in self.results if include_lost or r.status in good]
        if not sel:
            return Trajectory.empty()
        return Trajectory.from_matrices(np.array([r.t_us for r in sel], dtype=np.int64), np.stack([r.pose for r in sel]))
