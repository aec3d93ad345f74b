"""The EV-Pose ``TrackingSession`` as the player drives it: a shown session, a run-ahead session and a frame cache.

Two sessions over the same recording and configuration, both deterministic, so
step ``i`` of either is bit-identical to step ``i`` of a headless run:

- the **run-ahead** session only ever steps forward (plain steps, debug products
  only on the cache grid), in the player's idle time and between displayed
  frames. It fills the per-step summaries (plots, trajectory) and the
  :class:`~app.frame_cache.FrameCache`. It never restores: a restore costs a
  replay of the whole fusion log (``FactorGraphFusion.restore``), i.e. grows
  with the step it restores to.
- the **shown** session serves exact requests off the grid (step forward/back,
  exact seeks): it steps forward when it can and restores its own snapshots only
  when it must go back.

Playback and (grid-snapped) seeks inside the run-ahead's reach are answered from
the cache, costing a draw; past the run-ahead's frontier the cheapest session
steps there, at the tracker's own speed, which the player reports truthfully.
"""

from __future__ import annotations

import time

import numpy as np

from app.engine import Engine
from app.frame import Frame, StepSummary
from app.frame_cache import FrameCache, FrameCacheConfig, compact
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory

GOOD_STATUS = ("ok", "degraded")
"""Status values whose poses count as tracked (``TrackStatus.OK`` / ``DEGRADED``)."""


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
    """Shown session + run-ahead session + frame cache; see the module docstring."""

    def __init__(self, recording: Recording, contour_map: ContourMap, config=None, cache: FrameCacheConfig | None = None):
        from evpose.tracker.config import TrackerConfig

        self.recording = recording
        self.contour_map = contour_map
        self.config = config if isinstance(config, TrackerConfig) else TrackerConfig()
        self.explanation = ""
        self.session = self._new_session()
        """The shown session: exact requests off the cache grid."""
        self._ahead = None
        """The run-ahead session (created on the first prefetch); never restored."""
        cc = cache or FrameCacheConfig()
        every = max(1, int(round(cc.every_ms * 1e3 / self.session.dt_us)))
        self.cache = FrameCache(every, int(cc.budget_mb * 2**20))
        self._summaries: list[StepSummary] = []
        """Summary of every step computed so far by either session, by step index."""
        self._shown = -1
        """Index of the step on display (-1 before the first)."""
        self._step_s = {"plain": 0.0}
        """Running estimate of one tracker step without debug products (the tracker's own ``total`` timing), seconds."""
        self._restore_s_per_step = 0.0
        """Running estimate of a restore per step restored to, seconds (cost model)."""

    def _new_session(self):
        from evpose.tracker.session import TrackingSession

        return TrackingSession(self.recording, self.contour_map, self.config, initial_pose=None)

    # ------------------------------------------------------------------ views
    @property
    def step_us(self) -> int:
        return self.session.dt_us

    @property
    def n_steps(self) -> int:
        return self.session.total_steps

    @property
    def shown_index(self) -> int:
        return self._shown

    @property
    def frontier(self) -> int:
        """Steps the run-ahead has computed (0 before it starts)."""
        return 0 if self._ahead is None else self._ahead.step_count

    @property
    def history(self) -> list[StepSummary]:
        return self._summaries[: self._shown + 1]

    @property
    def current_t_us(self) -> int:
        return self._summaries[self._shown].t_us if self._shown >= 0 else self.t_start_us

    def trajectory(self) -> Trajectory:
        rows = [(s.t_us, s.pose) for s in self.history if s.status in GOOD_STATUS and s.pose is not None]
        if not rows:
            return Trajectory.empty()
        return Trajectory.from_matrices(np.array([r[0] for r in rows], np.int64), np.stack([r[1] for r in rows]))

    # ------------------------------------------------------------------ stepping
    def _role(self, s) -> str:
        return "ahead" if s is self._ahead else "shown"

    def _advance(self, s, debug: bool):
        """One step of session ``s``; records its summary and its display frame when on the grid.

        Only the run-ahead computes debug products to fill the grid; the shown session, which fills gaps
        behind it, computes them for the step asked for.
        """
        i = s.step_count
        role = self._role(s)
        grid = (role == "ahead" and self.cache.on_grid(i) and i not in self.cache and self.cache.nbytes < self.cache.budget)
        result = s.step(debug=debug or grid)
        if result is None:
            return None
        self._learn("plain", result.timings_ms.get("total", 0.0) * 1e-3)
        # The engine keeps the summaries itself; the session's result list (with debug images) would only grow.
        del s.results[:]
        if i == len(self._summaries):
            self._summaries.append(summary_from_result(result, i))
        frame = compact(frame_from_result(result, i)) if result.debug is not None else None
        if frame is not None and self.cache.on_grid(i) and self.cache.nbytes < self.cache.budget:
            self.cache.put(frame, near=max(self._shown, 0))
        return frame

    def _learn(self, key: str, seconds: float) -> None:
        if seconds > 0:
            old = self._step_s[key]
            self._step_s[key] = 0.9 * old + 0.1 * seconds if old else seconds

    def _step_to(self, s, k: int) -> Frame | None:
        """Step session ``s`` (at or before step ``k``) through step ``k``; the frame of step ``k``."""
        frame = None
        while s.step_count <= k:
            frame = self._advance(s, debug=s.step_count == k)
            if frame is None and s.done:
                return None
        return frame

    def _restore_for(self, s, k: int) -> None:
        """Put session ``s`` at or before step ``k`` through its nearest snapshot (cost grows with the snapshot's step)."""
        base = max(j for j in s.snapshot_steps if j <= k)
        t0 = time.perf_counter()
        s.restore_snapshot(base)
        if base > 0:
            per = (time.perf_counter() - t0) / base
            self._restore_s_per_step = per if not self._restore_s_per_step else 0.7 * self._restore_s_per_step + 0.3 * per

    def _forward_is_cheaper(self, s, k: int) -> bool:
        """Whether session ``s`` (at or before step ``k``) should step forward rather than restore its nearest snapshot."""
        plain = self._step_s["plain"] or 0.01
        base = max(j for j in s.snapshot_steps if j <= k)
        restore = base * (self._restore_s_per_step or 0.3 * plain) + (k - base + 1) * plain
        return (k - s.step_count + 1) * plain <= restore

    def _produce(self, k: int) -> Frame | None:
        """The exact frame of step ``k``; it becomes the shown step.

        Kept frames answer at once. Past the run-ahead's frontier the run-ahead itself steps there (unless the
        shown session is nearer), so every step on the way is kept for later seeks: a far jump costs the
        tracker's time once, then nothing. In a gap of the cache behind it, the shown session steps forward
        or restores, whichever is cheaper.
        """
        k = int(np.clip(k, 0, max(self.n_steps - 1, 0)))
        cached = self.cache.get(k)
        if cached is None:
            # Of the sessions that can step forward to k, the nearest (the run-ahead on a tie); else the shown one.
            ahead = self._ahead
            forward = ahead is not None and ahead.step_count <= k and (
                self.session.step_count > k or ahead.step_count >= self.session.step_count)
            s = ahead if forward else self.session
            if s.step_count > k or (s is self.session and not self._forward_is_cheaper(s, k)):
                self._restore_for(s, k)
            cached = self._step_to(s, k)
            if cached is None:
                return None
        self._shown = cached.index
        return cached

    # ------------------------------------------------------------------ Engine interface
    def step(self) -> Frame | None:
        if self._shown + 1 >= self.n_steps:
            return None
        return self._produce(self._shown + 1)

    def seek_step(self, index: int) -> Frame | None:
        return self._produce(index)

    def _index_at(self, t_us: int) -> int:
        """Index of the last step at or before ``t_us`` (the first step if none)."""
        s = self.session
        return int(np.clip((int(t_us) - s.t0_us) // s.dt_us, 1, max(s.total_steps, 1))) - 1

    def seek(self, t_us: int) -> Frame | None:
        return self._produce(self._index_at(t_us))

    def seek_near(self, t_us: int) -> Frame | None:
        """Like :meth:`seek`, but lands on the cache grid step at or before ``t_us`` (at most ``cache.every - 1`` steps earlier).

        A kept frame answers at once; otherwise the grid step is computed (and kept), which
        past the run-ahead's frontier is plain stepping rather than a restore.
        """
        k = self._index_at(t_us)
        g = k - k % self.cache.every
        hit = self.cache.latest_at_or_before(k, g)
        if hit is not None:
            self._shown = hit.index
            return hit
        return self._produce(g)

    def play_step(self, stride: int) -> Frame | None:
        """The next frame for playback, at most ``stride`` steps after the shown one (kept frames first)."""
        k0 = self._shown + 1
        last = self.n_steps - 1
        if k0 > last:
            return None
        hi = min(self._shown + max(int(stride), 1), last)
        hit = self.cache.latest_at_or_before(hi, k0)
        if hit is not None:
            self._shown = hit.index
            return hit
        g = hi - hi % self.cache.every
        return self._produce(g if g >= k0 else hi)

    def prefetch(self, budget_steps: int = 5) -> bool:
        """Run the run-ahead session ``budget_steps`` further; False once it has reached the end.

        The shown session and the shown step are untouched.
        """
        if self._ahead is None:
            self._ahead = self._new_session()
        s = self._ahead
        for _ in range(max(int(budget_steps), 1)):
            if s.done:
                break
            self._advance(s, debug=False)
            if s.step_count in s.snapshot_steps and s.step_count != 0:
                # Never restored, so its snapshots would only hold memory (several MB each).
                s.drop_snapshot(s.step_count)
        return not s.done
