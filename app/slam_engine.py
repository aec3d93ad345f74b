"""The map-free event SLAM (``evpose.slam.EventSlam``) as the player drives it: SLAM mode of the viewer.

Steps are fixed slices of events ``[t_start + k w, t_start + (k + 1) w)`` fed to
``EventSlam.step`` (as ``run_slam`` feeds them), so the state after step k
equals a headless ``run_slam(..., chunk_us=w)`` at that point. Seeking restores
the nearest earlier snapshot (``EventSlam.snapshot``, taken every
``snapshot_every`` steps) and replays the rest: deterministic, hence exact.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from app.engine import Engine, EventsOnlyEngine
from app.frame import Frame, SlamView, StepSummary
from app.slam_alignment import AtlasAligner, alignment_note
from evpose.core.events import EventArray
from evpose.core.trajectory import Trajectory
from evpose.core.recording import Recording
from evpose.errors import EvposeError
from evpose.slam import EventSlam, SlamConfig, SlamStepResult


@dataclass
class SlamViewConfig:
    """Settings of the viewer's SLAM mode."""

    step_us: int = field(default=5_000, metadata={"min": 1_000, "max": 50_000, "step": 1_000, "unit": "us"})
    """Events fed to SLAM per displayed step, microseconds (``run_slam``'s ``chunk_us``)."""
    snapshot_every: int = field(default=20, metadata={"min": 1, "max": 500, "step": 1, "unit": "steps"})
    """Steps between two seek snapshots (memory vs. replay time)."""
    slam: SlamConfig = field(default_factory=SlamConfig)


def slam_view(result: SlamStepResult, slam: EventSlam, aligner: AtlasAligner | None = None) -> SlamView:
    """The step's SLAM products; on a step without an MCI, those of the last MCI (so the panels do not blink).
    With an ``aligner``, every map of the atlas and its alignment to the ground truth too."""
    shown = result if result.mci is not None or not slam.results else slam.results[-1]
    m = slam.atlas.active
    kfs = np.stack([k.T_wc for k in m.keyframes]) if m is not None and m.keyframes else None
    # The active map as it is now (also between MCIs), not only as the last MCI left it.
    pts = np.array([p.xyz for p in m.points.values()], np.float64).reshape(-1, 3) if m is not None else None
    return SlamView(
        tiny_frame=result.tiny_frame, mci=shown.mci, hypothesis=shown.hypothesis, hypothesis_scores=dict(shown.hypothesis_scores),
        features=shown.features, feature_has_point=shown.feature_has_point, keyframe=result.keyframe, map_id=result.map_id,
        map_points=pts, keyframe_poses=kfs, mci_t_us=int(shown.t_us) if shown.mci is not None else None,
        atlas=aligner.views(slam.atlas) if aligner is not None else [],
        has_ground_truth=aligner is not None and aligner.ground_truth is not None and len(aligner.ground_truth) > 1,
    )


class SlamEngine(Engine):
    """SLAM mode: tiny frames, the selected MCI and its hypothesis scores, tracked features, keyframes and the growing map."""

    def __init__(self, recording: Recording, config: SlamViewConfig | None = None, explanation: str = ""):
        self.recording = recording
        self.config = config if isinstance(config, SlamViewConfig) else SlamViewConfig()
        gt = recording.ground_truth
        self.explanation = explanation or ("SLAM mode: no prior map; poses and map are in the active map's own frame"
                                           + (" and scale (event-only: arbitrary scale)." if self.config.slam.mode.value == "event" else ".")
                                           + (" The 3D view places each map on the ground truth (Umeyama alignment, for display"
                                              " only; 3D view > slam aligned)." if gt is not None and len(gt) > 1 else ""))
        # Raises InputError without calibration, or in event-inertial mode without IMU: the factory shows why.
        self.slam = EventSlam(self.config.slam, recording.calibration, recording.imu)
        self.width, self.height = self.slam.width, self.slam.height
        self._known: dict[int, StepSummary] = {}
        self._snapshots: dict[int, dict] = {0: self.slam.snapshot()}
        self._aligner = AtlasAligner(recording.ground_truth)
        """Display alignment of the atlas maps to the ground truth (never fed back into SLAM)."""
        self.step_count = 0
        """Steps applied to ``self.slam`` so far."""
        self._same_since = 0
        """Steps since which only empty windows were fed (SLAM's state is then unchanged: an empty window is a no-op,
        checked bit for bit on a pickled snapshot)."""

    # ---------------------------------------------------------------- steps
    @property
    def n_steps(self) -> int:
        return (self.t_end_us - self.t_start_us) // int(self.config.step_us) + 1

    def _window(self, k: int) -> EventArray:
        w = int(self.config.step_us)
        return self.recording.events.time_window(self.t_start_us + k * w, self.t_start_us + (k + 1) * w)

    @property
    def history(self) -> list[StepSummary]:
        return [self._known[i] for i in range(self.step_count)]

    def _advance(self) -> tuple[SlamStepResult, EventArray, float] | None:
        k = self.step_count
        if k >= self.n_steps:
            return None
        window = self._window(k)
        t0 = time.perf_counter()
        result = self.slam.step(window)
        if k == self.n_steps - 1:
            # The recording ends here: as run_slam, the events after the last reconstruction window make one more MCI
            # (EventWindowConfig.flush_min_fraction).
            end = self.slam.finish()
            if end is not None:
                end.mcis += result.mcis
                result = end
        elapsed = (time.perf_counter() - t0) * 1e3
        self.step_count = k + 1
        if len(window):
            self._same_since = self.step_count
        if self.step_count % int(self.config.snapshot_every) == 0 and self.step_count not in self._snapshots:
            # Inside a stretch without events the state is the last snapshot's: shared, not copied again (a deep
            # copy of the map, 45 ms on the demo landing, every 20 steps of a 60 s gap). restore() copies it.
            # Seeks into a 60 s gap after 2 s of the demo landing: to 30 s 8.9 -> 3.5 s, then to 61.9 s 8.1 -> 0.9 s.
            prev = max(j for j in self._snapshots if j < self.step_count)
            same = prev >= self._same_since
            self._snapshots[self.step_count] = self._snapshots[prev] if same else self.slam.snapshot()
        timings = dict(result.timings_ms) if result.mcis else {}
        timings["step"] = elapsed
        counts = {**result.counts, "events_in": len(window), "events_kept": len(window), "mcis": result.mcis,
                  "window_events": result.n_events_window, "map_id": result.map_id}
        self._known[k] = StepSummary(k, self._step_t(k), result.pose, None, result.status.value, timings, counts)
        return result, window, elapsed

    def _skip_empty(self, limit: int) -> int:
        """Go over the steps without events up to step ``limit`` (exclusive) at once, as :meth:`_advance` would have
        made them; the number gone over. Only once an empty window has been fed: SLAM's state is then that of every
        further empty step (an empty window is a no-op), and so is the step's result, so each such step's summary is
        the last one at its own index and time (its ``step`` time 0: not computed). Session 27, the 60 s gap of
        ``/tmp/s26/ui26/gapdata/gap60.h5`` (``/tmp/s27/ui27/p_gap.py``, main vs this): seek from the start to just past
        it 6.35 -> 4.32 s (the 2 s before the gap, with events, cost 4.2 s of it), the gap as one play stride 0.29 ->
        0.12 s (one seek snapshot copied at its start); the viewer playing it at 1x from 1.8 s to 62.2 s 3.8 -> 3.5 s
        wall (``a9_slamgap.py``: the player already went over it in few strides)."""
        k = self.step_count
        if k == 0 or self._same_since >= k:
            return 0
        w, t = int(self.config.step_us), self.recording.events.t
        i = int(np.searchsorted(t, self.t_start_us + k * w, "left"))
        first_with_events = self.n_steps if i >= len(t) else (int(t[i]) - self.t_start_us) // w
        end = min(first_with_events, limit, self.n_steps)
        if end <= k:
            return 0
        last = self._known[k - 1]
        every = int(self.config.snapshot_every)
        for j in range(k, end):
            self._known[j] = dataclasses.replace(last, index=j, t_us=self._step_t(j), timings_ms={"step": 0.0},
                                                 counts=dict(last.counts))
            if (j + 1) % every == 0 and (j + 1) not in self._snapshots:
                prev = max(n for n in self._snapshots if n < j + 1)
                same = prev >= self._same_since  # as _advance: shared within the stretch, taken once at its start
                self._snapshots[j + 1] = self._snapshots[prev] if same else self.slam.snapshot()
        self.step_count = end
        return end - k

    play_stops_at_events = True
    """:meth:`play_step` ends its stride where events come again after a stretch without (the player may then
    stride far over such a stretch)."""

    @property
    def step_us(self) -> int:
        return int(self.config.step_us)

    def play_step(self, stride: int) -> Frame | None:
        """The step ``stride`` steps on (the last one at most): the steps before it are computed without their
        display products, which the player would not draw (it draws at most ``max_ui_fps`` frames a second); the
        atlas alignment of each frame's view cost 8 of the 13 ms of an empty step (a 60 s gap: 156 s at 1x; now
        ~12 s, ``/tmp/s26/ui26/a1_gap.py``). Playing the demo landing from its start for 10 s (session 26,
        ``/tmp/s26/ui26/b_slamplay.py``): real-time factor 0.086 -> 0.258, 91 -> 123 frames drawn."""
        target = self.step_count + min(max(int(stride), 1), self.n_steps - self.step_count) - 1
        while self.step_count < target:
            if self._same_since < self.step_count and len(self._window(self.step_count)):
                break  # events again after a stretch without: their first step is shown, not one a long stride on
            if not self._skip_empty(target):
                self._advance()
        return self.step()

    def _step_t(self, k: int) -> int:
        return self.t_start_us + (k + 1) * int(self.config.step_us)

    def step(self) -> Frame | None:
        out = self._advance()
        if out is None:
            return None
        result, window, _ = out
        k = self.step_count - 1
        s = self._known[k]
        shape = (self.height, self.width)
        tiny = result.tiny_frame if result.tiny_frame is not None else np.zeros(shape, np.float32)
        empty = np.zeros(shape, np.float32)
        return Frame(index=k, t_us=s.t_us, ts_positive=tiny, ts_negative=empty, tdf=result.mci if result.mci is not None else empty,
                     events_kept=window, events_removed=EventArray.empty(), pose=result.pose, status=s.status,
                     reason=result.reason, timings_ms=dict(s.timings_ms), counts=dict(s.counts),
                     slam=slam_view(result, self.slam, self._aligner))

    def _goto(self, k: int) -> None:
        """Put SLAM in the state after ``k`` steps: restore the best snapshot at or before k, replay the rest."""
        if not (max(j for j in self._snapshots if j <= max(k, 0)) <= self.step_count <= k):
            base = max(j for j in self._snapshots if j <= k)
            self._restore(base)
        while self.step_count < k and (self._skip_empty(k) or self._advance() is not None):
            pass

    def _restore(self, k: int) -> None:
        self.slam.restore(self._snapshots[k])
        self.step_count = self._same_since = k  # the state is snapshot k's

    def _index_at(self, t_us: int) -> int:
        return int(np.clip((int(t_us) - self.t_start_us) // int(self.config.step_us) - 1, 0, self.n_steps - 1))

    def _start_for(self, k: int) -> int:
        """Step SLAM would replay from to reach ``k``: where it is, or the best snapshot at or before ``k``."""
        base = max(j for j in self._snapshots if j <= k)
        return self.step_count if base <= self.step_count <= k else base

    def catch_up_steps(self, t_us: int, exact: bool = False) -> int:
        k = self._index_at(t_us)
        return k - self._start_for(k)

    def catch_up(self, t_us: int, budget_steps: int, exact: bool = False) -> bool:
        """Replay towards the seek's step without making its images (snapshots are kept on the way)."""
        k = self._index_at(t_us)
        start = self._start_for(k)
        if start != self.step_count:
            self._restore(start)
        for _ in range(max(int(budget_steps), 1)):  # a stretch without events gone over at once counts as one step
            if self.step_count >= k or not (self._skip_empty(k) or self._advance() is not None):
                break
        return self.step_count >= k

    def catch_up_progress(self, t_us: int, exact: bool = False) -> tuple[float, float]:
        k = self._index_at(t_us)
        w = int(self.config.step_us)
        return self._start_for(k) * w / 1e6, (k + 1) * w / 1e6

    def seek_step(self, index: int) -> Frame | None:
        k = int(np.clip(index, 0, self.n_steps - 1))
        self._goto(k)
        return self.step()

    def seek(self, t_us: int) -> Frame | None:
        return self.seek_step(self._index_at(t_us))

    def trajectory(self) -> Trajectory:
        """The active map's poses so far, refined by its bundle adjustments (as ``evpose slam`` writes them).

        Per-step poses of different maps live in different frames (and, event-only, scales), so
        exporting them together would draw jumps that are not motion.
        """
        m = self.slam.atlas.active
        return m.trajectory(refined=True) if m is not None else Trajectory.empty()


def slam_engine_factory(recording):
    """A config -> SlamEngine function; without calibration (or IMU in event-inertial mode) the events-only view says why."""
    def make(cfg):
        try:
            return SlamEngine(recording, cfg if isinstance(cfg, SlamViewConfig) else None)
        except EvposeError as exc:
            return EventsOnlyEngine(recording, None, explanation=f"SLAM cannot start: {exc}")

    return make


def slam_markdown(frame: Frame, aligned: bool = True, t0_us: int = 0) -> str:
    """The SLAM step in words: selected MCI hypothesis and every hypothesis' score, tracks, keyframe, map size,
    and how the 3D view places the maps (``aligned``: on the ground truth, when there is one)."""
    v = frame.slam
    scores = ", ".join(f"{'**' + k + '**' if k == v.hypothesis else k} {s:.4f}" for k, s in sorted(v.hypothesis_scores.items()))
    n_feat = 0 if v.features is None else len(v.features)
    with_pt = 0 if v.feature_has_point is None else int(np.count_nonzero(v.feature_has_point))
    n_pts = 0 if v.map_points is None else len(v.map_points)
    n_kf = 0 if v.keyframe_poses is None else len(v.keyframe_poses)
    # Before the first map its id is -1: "map -1: 0 points" read like a broken map.
    head = (f"map {v.map_id}: {n_pts} points, {n_kf} keyframes{' (keyframe inserted)' if v.keyframe else ''}" if v.map_id >= 0
            else "no map yet: SLAM starts its first one with a two-view initialisation from the tracked features")
    return (f"{head}\n\n"
            f"MCI{'' if v.mci_t_us is None else f' at {(v.mci_t_us - t0_us) / 1e6:.3f} s'} hypothesis scores (mean local STD): {scores or 'no MCI yet'}\n\n"
            f"tracked features: {n_feat} ({with_pt} with a map point; green with, yellow without)"
            + (f"\n\n{note}" if (note := alignment_note(v.atlas, aligned, v.has_ground_truth)) else ""))
