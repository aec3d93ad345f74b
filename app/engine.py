"""Engines the player drives: the EV-Pose tracker session, or an events-only view when there is no map.

Both expose the same small interface (``step``, ``seek``, ``history``,
``trajectory``) and both are deterministic: the state after ``seek(t)`` equals
the state an uninterrupted headless run reaches at ``t``.
"""

from __future__ import annotations

import dataclasses
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from app.frame import Frame, StepSummary
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.frontend.distance_field import DistanceFieldConfig, TemporalDistanceField
from evpose.frontend.time_surface import SeparatedTimeSurface, TimeSurfaceConfig


class Engine(ABC):
    """A steppable, seekable computation over one recording."""

    recording: Recording
    config: object
    history: list[StepSummary]
    explanation: str = ""
    """Plain-words note shown to the user about what this engine can and cannot do."""

    @property
    def t_start_us(self) -> int:
        return self.recording.t_start_us

    @property
    def t_end_us(self) -> int:
        return self.recording.t_end_us

    @abstractmethod
    def step(self) -> Frame | None:
        """Compute the next step with images; None at the end of the recording."""

    @abstractmethod
    def seek(self, t_us: int) -> Frame | None:
        """Go to the last step at or before ``t_us`` (the first step if none) and return its frame."""

    def seek_step(self, index: int) -> Frame | None:
        """Go to step ``index`` (of the steps computed so far) and return its frame."""
        hist = self.history
        if not hist:
            return self.seek(self.t_start_us)
        return self.seek(hist[min(max(index, 0), len(hist) - 1)].t_us)

    @property
    def current_t_us(self) -> int:
        return self.history[-1].t_us if self.history else self.t_start_us

    def prefetch(self, budget_steps: int) -> bool:
        """Use idle time to make later seeks fast, leaving the displayed state as it is; False when nothing is left to do."""
        return False

    def trajectory(self) -> Trajectory:
        """Estimated poses of the steps so far (steps without a pose are left out)."""
        rows = [(s.t_us, s.pose) for s in self.history if s.pose is not None]
        if not rows:
            return Trajectory.empty()
        return Trajectory.from_matrices(np.array([r[0] for r in rows]), np.stack([r[1] for r in rows]))


@dataclass
class EventsViewConfig:
    """Settings of the events-only view (recordings without a map): the tracker's own front-end stages."""

    window_us: int = field(default=5_000, metadata={"min": 1_000, "max": 100_000, "step": 1_000, "unit": "us"})
    """Time between two displayed steps, microseconds."""
    time_surface: TimeSurfaceConfig = field(default_factory=TimeSurfaceConfig)
    distance_field: DistanceFieldConfig = field(default_factory=DistanceFieldConfig)


class EventsOnlyEngine(Engine):
    """SP-TS and TDF images from the events alone; used when there is no map or tracking cannot start.

    Uses the tracker's ``SeparatedTimeSurface`` and ``TemporalDistanceField``.
    Steps are fixed windows ``t_k = t_start + (k + 1) * window``; the state at a
    step is a pure function of the events before it, so a seek rebuilds it
    exactly from the start (one pass of a numba kernel).
    """

    def __init__(self, recording: Recording, config: EventsViewConfig | None = None, explanation: str = ""):
        self.recording = recording
        self.config = config if isinstance(config, EventsViewConfig) else EventsViewConfig()
        self.explanation = explanation
        size = recording.sensor_size
        if size is None:
            ev = recording.events
            size = (int(ev.x.max()) + 1, int(ev.y.max()) + 1) if len(ev) else (1, 1)
        self.width, self.height = size
        self.history = []
        self._surface = SeparatedTimeSurface(self.config.time_surface, self.width, self.height, recording.calibration)
        self._field = TemporalDistanceField(self.config.distance_field, self.width, self.height)
        self._next_index = 0

    def _step_time(self, index: int) -> int:
        return self.t_start_us + (index + 1) * int(self.config.window_us)

    @property
    def n_steps(self) -> int:
        # Enough windows that the last one contains the final event (windows are [t - w, t)).
        return (self.t_end_us - self.t_start_us) // int(self.config.window_us) + 1

    def _frame(self, index: int, window: EventArray, elapsed_ms: float) -> Frame:
        t = self._step_time(index)
        t0 = time.perf_counter()
        pos = self._surface.image(t, 1)
        neg = self._surface.image(t, -1)
        t1 = time.perf_counter()
        self._field.compute(self._surface, t, polarities=(0,))
        tdf = self._field.image(0)
        t2 = time.perf_counter()
        timings = {"time_surface": (t1 - t0) * 1e3 + elapsed_ms, "distance_field": (t2 - t1) * 1e3}
        timings["total"] = sum(timings.values())
        return Frame(
            index=index, t_us=t, ts_positive=pos, ts_negative=neg, tdf=tdf,
            events_kept=window, events_removed=EventArray.empty(),
            status="events only", reason=self.explanation, timings_ms=timings,
            counts={"events_in": len(window), "events_kept": len(window)},
        )

    def step(self) -> Frame | None:
        k = self._next_index
        if k >= self.n_steps:
            return None
        t0 = time.perf_counter()
        window = self.recording.events.time_window(self._step_time(k) - int(self.config.window_us), self._step_time(k))
        self._surface.update(window)
        frame = self._frame(k, window, (time.perf_counter() - t0) * 1e3)
        self.history.append(StepSummary.of(frame))
        self._next_index = k + 1
        return frame

    def seek_step(self, index: int) -> Frame | None:
        return self.seek(self._step_time(min(max(index, 0), self.n_steps - 1)))

    def seek(self, t_us: int) -> Frame | None:
        w = int(self.config.window_us)
        k = int(np.clip((int(t_us) - self.t_start_us) // w - 1, 0, self.n_steps - 1))
        ev = self.recording.events
        t_k = self._step_time(k)
        self._surface.reset()
        self._surface.update(ev.time_window(ev.t[0] if len(ev) else 0, t_k - w))
        # Summaries of the skipped steps: counts are exact, timings were not measured.
        bounds = np.searchsorted(ev.t, self._step_time(np.arange(-1, k)), side="left")
        counts = np.diff(bounds)
        self.history = [
            StepSummary(i, self._step_time(i), None, None, "events only", {}, {"events_in": int(c), "events_kept": int(c)})
            for i, c in enumerate(counts)
        ]
        self._next_index = k
        return self.step()


def frame_from_result(result, index: int) -> Frame:
    """Convert a tracker ``StepResult`` (with debug products) into a displayed frame."""
    d = result.debug
    imu = result.imu_poses.matrices() if result.imu_poses is not None and len(result.imu_poses) else None
    if d is None:
        empty = np.zeros((1, 1), np.float32)
        return Frame(index, int(result.t_us), empty, empty, empty, EventArray.empty(), EventArray.empty(),
                     pose=result.pose, registration_pose=result.registration_pose, status=result.status.value,
                     reason=result.reason, imu_poses=imu, timings_ms=dict(result.timings_ms), counts=dict(result.counts))
    return Frame(
        index=index, t_us=int(result.t_us), ts_positive=d.ts_positive, ts_negative=d.ts_negative, tdf=d.tdf,
        events_kept=d.events_kept, events_removed=d.events_removed, pose=result.pose,
        registration_pose=result.registration_pose, status=result.status.value, reason=result.reason,
        point_index=d.point_index, visible_index=d.visible_index, projected_uv=d.projected_uv,
        residuals=d.residuals, weights=d.weights, predicted_polarity=d.predicted_polarity, imu_poses=imu,
        timings_ms=dict(result.timings_ms), counts=dict(result.counts),
    )


def summary_from_result(result, index: int) -> StepSummary:
    return StepSummary(index, int(result.t_us), result.pose, result.registration_pose, result.status.value,
                       dict(result.timings_ms), dict(result.counts))


class TrackerEngine(Engine):
    """The EV-Pose ``TrackingSession`` (evpose/tracker/session.py) as the player drives it.

    Seeking and idle-time prefetch work on the session's snapshots. The engine
    keeps every StepResult it has seen (without debug images) so that after
    restoring a snapshot *ahead* of the current step the session's ``results``
    can be filled in; all steps are deterministic, so a cached result equals a
    recomputed one. This uses the session's private snapshot table; a public
    ``TrackingSession.snapshot_here()/restore_to(step)`` would remove that.
    """

    def __init__(self, recording: Recording, contour_map: ContourMap, config=None):
        from evpose.tracker.config import TrackerConfig
        from evpose.tracker.session import TrackingSession

        self.recording = recording
        self.contour_map = contour_map
        self.config = config if isinstance(config, TrackerConfig) else TrackerConfig()
        self.session = TrackingSession(recording, contour_map, self.config, initial_pose=None)
        self.explanation = ""
        self._known: dict[int, object] = {}
        """Step index -> StepResult (debug dropped) of every step computed so far."""
        self._extra: set[int] = set()
        """Snapshots this engine added off the session's grid (shown step, prefetch frontier)."""

    @property
    def history(self) -> list[StepSummary]:
        return [summary_from_result(r, i) for i, r in enumerate(self.session.results)]

    @property
    def current_t_us(self) -> int:
        res = self.session.results
        return int(res[-1].t_us) if res else self.t_start_us

    def trajectory(self) -> Trajectory:
        return self.session.trajectory()

    def _remember(self, result) -> None:
        self._known[self.session.step_count - 1] = dataclasses.replace(result, debug=None)

    def _plain_step(self):
        result = self.session.step()
        if result is not None:
            self._remember(result)
        return result

    def step(self) -> Frame | None:
        result = self.session.step(debug=True)
        if result is None:
            return None
        self._remember(result)
        return frame_from_result(result, len(self.session.results) - 1)

    def _goto(self, k: int) -> None:
        """Put the session in the state after ``k`` steps: restore the best snapshot, replay the rest."""
        s = self.session
        base = max(j for j in s.snapshot_steps if j <= k)
        if not (base <= s.step_count <= k):
            s.restore_snapshot(base)
            # Restoring ahead of the computed results: fill them from the cache.
            s.results.extend(self._known[i] for i in range(len(s.results), base))
        while s.step_count < k and self._plain_step() is not None:
            pass

    def _mark(self) -> None:
        s = self.session
        if s.step_count not in s.snapshot_steps:
            self._extra.add(s.take_snapshot())

    def seek_step(self, index: int) -> Frame | None:
        k = int(np.clip(index, 0, max(self.session.total_steps - 1, 0)))
        self._goto(k)
        return self.step()

    def prefetch(self, budget_steps: int = 5) -> bool:
        """Run a few steps past the furthest snapshot, snapshot there, come back to the shown step.

        Each slice costs two restores and ``budget_steps`` steps, so a command
        waits at most one slice; once the furthest snapshot reaches the end, any
        seek replays at most ``snapshot_every`` steps. The shown state is
        unchanged (same deterministic steps).
        """
        s = self.session
        frontier = s.snapshot_steps[-1]
        if frontier >= s.total_steps:
            return False
        shown = s.step_count
        self._mark()
        self._goto(frontier)
        for _ in range(max(budget_steps, 1)):
            if self._plain_step() is None:
                break
        self._mark()
        reached = s.step_count
        for j in list(self._extra):  # keep only the shown step and the new frontier off the grid
            if j not in (shown, reached):
                s.drop_snapshot(j)
                self._extra.discard(j)
        self._goto(shown)
        return reached < s.total_steps

    def seek(self, t_us: int) -> Frame | None:
        # The state after the step before the target, then the target step itself with debug products.
        s = self.session
        k = int(np.clip((int(t_us) - s.t0_us) // s.dt_us, 1, max(s.total_steps, 1)))
        return self.seek_step(k - 1)
