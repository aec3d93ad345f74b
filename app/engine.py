"""Engines the player drives: the base interface and the events-only view (no map); the tracker's is in ``app/tracker_engine.py``.

All expose the same small interface (``step``, ``seek``, ``history``,
``trajectory``) and all are deterministic: the state after ``seek(t)`` equals
the state an uninterrupted headless run reaches at ``t``.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from app.frame import Frame, StepSummary
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

    def is_last(self, frame: Frame) -> bool:
        """``frame`` is the recording's last step. Its time lies up to a step before the last event (landing demo:
        3.995 of 3.999995 s), so the step count decides where the engine knows it."""
        n = getattr(self, "n_steps", None)
        return frame.t_us >= self.t_end_us or (n is not None and frame.index >= n - 1)

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

    step_us: int | None = None
    """Media time between two steps, microseconds (None: unknown; playback then asks for every step)."""

    def play_step(self, stride: int) -> Frame | None:
        """The next frame for playback, at most ``stride`` steps on; engines without a frame cache compute every step."""
        return self.step()

    def seek_near(self, t_us: int) -> Frame | None:
        """A seek that may land a few steps before ``t_us`` when that answers faster (default: exact)."""
        return self.seek(t_us)

    def catch_up_steps(self, t_us: int, exact: bool = False) -> int:
        """Steps to compute before a seek to ``t_us`` answers (``exact``: :meth:`seek`, else :meth:`seek_near`);
        0 when it answers at once, or when the engine cannot say (its seeks are then made in one go)."""
        return 0

    def catch_up_cost_steps(self, t_us: int, exact: bool = False) -> int:
        """:meth:`catch_up_steps` plus what else the seek must do first (a snapshot to restore), in steps of CPU
        time: the player slices a seek above ``catch_up_steps`` of it."""
        return self.catch_up_steps(t_us, exact)

    def catch_up(self, t_us: int, budget_steps: int, exact: bool = False) -> bool:
        """Compute at most ``budget_steps`` of those steps, the cheapest way (no display products on the way);
        True once none are left. The player calls it in slices so commands are heard in between."""
        return True

    def preview(self, t_us: int, exact: bool = False) -> Frame | None:
        """What can be shown of the step a seek to ``t_us`` lands on before it is computed (``Frame.preview``),
        cheaply; None when the engine has nothing such (the player then shows the progress alone)."""
        return None

    def catch_up_progress(self, t_us: int, exact: bool = False) -> tuple[float, float]:
        """(media seconds reached, media seconds of the target) of a catch-up towards ``t_us``, from the start."""
        return ((self.current_t_us - self.t_start_us) / 1e6, (int(t_us) - self.t_start_us) / 1e6)

    def release(self) -> None:
        """Called once the player lets this engine go (another recording or configuration): finish background work."""

    def trajectory(self) -> Trajectory:
        """Estimated poses of the steps so far (steps without a pose are left out)."""
        rows = [(s.t_us, s.pose) for s in self.history if s.pose is not None]
        if not rows:
            return Trajectory.empty()
        return Trajectory.from_matrices(np.array([r[0] for r in rows]), np.stack([r[1] for r in rows]))


QUIET_RUN_US = 1_000_000
"""Most media time without events the events-only view goes over in one playback step, microseconds."""


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

    def __init__(self, recording: Recording, config: EventsViewConfig | None = None, explanation: str = "",
                 cause: Exception | None = None):
        self.recording = recording
        self.config = config if isinstance(config, EventsViewConfig) else EventsViewConfig()
        self.explanation = explanation
        self.cause = cause
        """The error that kept the tracker from starting (None: there was no map, or no tracker in this build)."""
        self.rejected_config = None
        """The tracker configuration it could not start with, when one was asked for (the viewer keeps its controls)."""
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

    def play_step(self, stride: int) -> Frame | None:
        """The next step; when its window has no events, the run of such windows is gone over (their summaries kept,
        no images made) up to the first step with events or :data:`QUIET_RUN_US` of them. Made one by one, a 60 s
        gap took over a minute to play (images and field of every empty step), while there is nothing to see."""
        ev = self.recording.events
        k, last, w = self._next_index, self.n_steps - 1, int(self.config.window_us)
        first = k
        while k < last and (k - first) * w < QUIET_RUN_US:
            lo, hi = ev.index_range(self._step_time(k) - w, self._step_time(k))
            if hi > lo:
                break
            self.history.append(StepSummary(k, self._step_time(k), None, None, "events only", {}, {"events_in": 0, "events_kept": 0}))
            k += 1
        self._next_index = k
        return self.step()

    def seek_step(self, index: int) -> Frame | None:
        return self.seek(self._step_time(min(max(index, 0), self.n_steps - 1)))

    def seek(self, t_us: int) -> Frame | None:
        w = int(self.config.window_us)
        k = int(np.clip((int(t_us) - self.t_start_us) // w - 1, 0, self.n_steps - 1))
        ev = self.recording.events
        t_k = self._step_time(k)
        self._surface.reset()
        self._surface.update(ev.time_window(ev.t[0] if len(ev) else 0, t_k - w))
        # Summaries of the skipped steps: counts are exact, timings were not measured unless the step was computed
        # before (kept: a step forward after playing seeks, and the latency plot then said the played steps were untimed).
        bounds = np.searchsorted(ev.t, self._step_time(np.arange(-1, k)), side="left")
        counts = np.diff(bounds)
        timed = {s.index: s for s in self.history[:k] if s.timings_ms}
        self.history = [
            timed.get(i) or StepSummary(i, self._step_time(i), None, None, "events only", {}, {"events_in": int(c), "events_kept": int(c)})
            for i, c in enumerate(counts)
        ]
        self._next_index = k
        return self.step()
