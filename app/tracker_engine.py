"""The EV-Pose ``TrackingSession`` as the player drives it: a shown session, a run-ahead session and a frame cache.

Two sessions over the same recording and configuration, both deterministic, so
step ``i`` of either is bit-identical to step ``i`` of a headless run:

- the **run-ahead** session only ever steps forward, in the player's idle time
  and between displayed frames. It steps plain (no debug products) except on
  the frame grid (``FrameCacheConfig.every_ms``), fills the per-step summaries
  (plots, trajectory) and the :class:`~app.frame_cache.FrameCache`, and keeps its
  regular snapshots (``TrackerConfig.snapshot_every``) for the shown session.
- the **shown** session serves exact requests off the grid (step forward/back,
  exact seeks): it steps forward when that is cheaper, else restores the nearest
  snapshot at or before the step, its own or one the run-ahead left behind
  (restoring copies the state, so one snapshot serves both sessions).

Playback and (grid-snapped) seeks inside the run-ahead's reach are answered from
the cache, costing a draw; past the run-ahead's frontier the run-ahead steps
there, at the tracker's own speed, which the player reports truthfully.

A seek far past the frontier is a *catch-up* when the player drives it
(:meth:`TrackerEngine.catch_up`, in slices): the run-ahead steps there plainly,
without the grid's debug products and kept frames (about a third of its cost),
keeping only its snapshots and the summaries; the target step is then computed
with its debug products. The grid frames it passed are filled in once the
run-ahead is done (:meth:`TrackerEngine._backfill`); seeks there meanwhile
restore a snapshot and replay a few steps.

With a :class:`~app.disk_cache.DiskCache`, summaries and kept frames of an
earlier opening (same recording, map, configuration and code) are read back at
start, and chunks the run-ahead completes are written out, with an engine
snapshot at each chunk's end (``app/disk_snapshots.py``). A seek past the
in-memory frontier restores the farthest disk snapshot at or before it (the
run-ahead jumps there when it is the one to step on) rather than stepping from
step 0 or from where the run-ahead is.
"""

from __future__ import annotations

import time

import numpy as np

from app.disk_cache import DiskCache
from app.disk_snapshots import DiskSnapshotsMixin, array_nbytes, share_snapshot, start_journals
from app.engine import Engine
from app.frame import Frame, StepSummary, frame_from_result, imageless_frame, summary_from_result
from app.frame_cache import FrameCache, FrameCacheConfig, compact
from evpose.core.contour_map import ContourMap
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory

GOOD_STATUS = ("ok", "degraded")
"""Status values whose poses count as tracked (``TrackStatus.OK`` / ``DEGRADED``)."""


class TrackerEngine(DiskSnapshotsMixin, Engine):
    """Shown session + run-ahead session + frame cache; see the module docstring."""

    def __init__(self, recording: Recording, contour_map: ContourMap, config=None, cache: FrameCacheConfig | None = None,
                 disk=None):
        """``disk``: None, or a function ``(config, every_steps) -> DiskCache | None`` giving this configuration's cache entry."""
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
        self._snapshot_budget = cc.snapshot_budget_mb * 2**20
        self._snapshot_spacing = max(1, int(round(cc.snapshot_every_ms * 1e3 / self.session.dt_us)))
        """Steps between two snapshots the run-ahead keeps (doubles whenever they outgrow their budget)."""
        self._snapshot_bytes = 0
        """Bytes of arrays in one run-ahead snapshot (measured on the first one past step 0)."""
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
        self.disk: DiskCache | None = disk(self.config, every) if disk is not None else None
        self._disk_steps = 0
        """Steps whose summaries (and kept frames) came from the disk cache."""
        self._unkept: set[int] = set()
        """Grid steps a catch-up passed without keeping their frame; :meth:`prefetch` fills them in later."""
        self._disk_queue, self._disk_adopted = [], {}
        if self.disk is not None:
            summaries, frames = self.disk.load()
            self._summaries = summaries
            self._disk_steps = len(summaries)
            for k in sorted(frames):
                self.cache.put_packed(k, frames[k], near=0)
            self.disk.snapshot_chunks()

    def _new_session(self):
        from evpose.tracker.session import TrackingSession

        from evpose.tracker.map_acquisition import DEFAULT_ACQUIRE_S

        s = TrackingSession(self.recording, self.contour_map, self.config, initial_pose=None)
        # The acquisition window's updates count their chance level: the wrong-map warning and ``--prepare`` read it.
        s.tracker.chance_until_us = s.t0_us + int(round(DEFAULT_ACQUIRE_S * 1e6))
        return s

    def _new_ahead(self):
        """The run-ahead session; with a disk cache its fusion journals its calls for the disk snapshots."""
        s = self._new_session()
        if self.disk is not None and self.disk.config.snapshots:
            start_journals(s.tracker)
        return s

    # ------------------------------------------------------------------ views
    @property
    def step_us(self) -> int:
        return self.session.dt_us

    @property
    def n_steps(self) -> int:
        return self.session.total_steps

    def seconds_of_steps(self, k: int) -> float:
        """Seconds of recording the first ``k`` steps cover (``k * step_us`` until the first long event gap)."""
        s = self.session
        return (s.time_of(k) - s.time_of(0)) / 1e6

    @property
    def shown_index(self) -> int:
        return self._shown

    @property
    def frontier(self) -> int:
        """Steps the run-ahead has computed (0 before it starts)."""
        return 0 if self._ahead is None else self._ahead.step_count

    @property
    def disk_steps(self) -> int:
        """Steps whose summaries (and kept frames) were read from the disk cache at start."""
        return self._disk_steps

    @property
    def ready_steps(self) -> int:
        """Steps from the start that are known (computed by the run-ahead or read from disk): seeks there answer at once."""
        return max(self.frontier, self._disk_steps)

    @property
    def backfill_left(self) -> int:
        """Kept frames a catch-up skipped that are still to be filled in (after the run-ahead is done)."""
        return len(self._unkept)

    @property
    def history(self) -> list[StepSummary]:
        return self._summaries[: self._shown + 1]

    @property
    def known_summaries(self) -> list[StepSummary]:
        """Summaries of every step from the start known so far (computed by either session or read from disk)."""
        return self._summaries

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

    def _advance(self, s, debug: bool, fill: bool = True):
        """One step of session ``s``; records its summary and its display frame when on the grid.

        Only the run-ahead computes debug products to fill the grid (unless ``fill`` is False: a catch-up,
        which notes the grid steps it passes); the shown session, which fills gaps behind it, computes them
        for the step asked for.
        """
        i = s.step_count
        role = self._role(s)
        on_grid = self.cache.on_grid(i) and i not in self.cache
        wanted = role == "ahead" and on_grid and self.cache.nbytes < self.cache.budget
        grid = fill and wanted
        if wanted and not fill and not debug:
            self._unkept.add(i)  # a frame the run-ahead would have kept: filled in later
        result = s.step(debug=debug or grid)
        if result is None:
            return None
        self._learn("plain", result.timings_ms.get("total", 0.0) * 1e-3)
        # The engine keeps the summaries itself; the session's result list (with debug images) would only grow.
        del s.results[:]
        if i == len(self._summaries):
            self._summaries.append(summary_from_result(result, i))
        frame = compact(frame_from_result(result, i)) if result.debug is not None else None
        if frame is None and debug:
            # The update standing for a long event gap makes no images. Without a frame, "forward >" at the last
            # step before a 60 s gap did nothing (the player redrew that step), and "< back" after it likewise.
            cal = self.recording.calibration
            frame = imageless_frame(result, i, self.recording.sensor_size or (cal.width, cal.height))
        if frame is not None and self.cache.on_grid(i) and self.cache.nbytes < self.cache.budget:
            self.cache.put(frame, near=max(self._shown, 0))
            self._unkept.discard(i)
        if role == "ahead":
            if self.disk is not None:
                self._write_disk_snapshot(s, defer=not fill)
            self._thin_snapshots(s)
            if self.disk is not None:
                self._maybe_write_chunk(i)
        return frame

    def _thin_snapshots(self, s) -> None:
        """Keep a run-ahead snapshot every ``_snapshot_spacing`` steps (the session's own regular ones elsewhere go),
        within the memory budget: past it, every other one goes."""
        k = s.step_count
        if k == 0:
            return
        if k % self._snapshot_spacing == 0 and k not in s.snapshot_steps:
            s.take_snapshot()
        if k not in s.snapshot_steps:
            return
        if not self._snapshot_bytes:
            self._snapshot_bytes = max(array_nbytes(s.snapshot_at(k)), 1)
        if k % self._snapshot_spacing:
            s.drop_snapshot(k)
            return
        while len(s.snapshot_steps) * self._snapshot_bytes > self._snapshot_budget and len(s.snapshot_steps) > 2:
            self._snapshot_spacing *= 2
            for j in s.snapshot_steps:
                if j % self._snapshot_spacing:
                    s.drop_snapshot(j)

    def _maybe_write_chunk(self, i: int) -> None:
        """Write the disk chunk that step ``i`` (just made by the run-ahead) completes, if it is wanted."""
        c = self.disk.chunk_steps
        if (i + 1) % c == 0 or i + 1 == self.n_steps:
            self._write_chunk_if_ready(i // c)

    def _write_chunk_if_ready(self, n: int) -> None:
        """Write disk chunk ``n`` if it is wanted, all its steps are known and it has all its grid frames
        (a chunk a catch-up passed waits for :meth:`_backfill`)."""
        c = self.disk.chunk_steps
        lo, hi = n * c, min((n + 1) * c, self.n_steps) - 1
        if not self.disk.want(n) or len(self._summaries) <= hi or any(lo <= j <= hi for j in self._unkept):
            return
        frames = {k: e for k in range(lo, hi + 1) if (e := self.cache.packed(k)) is not None}
        self.disk.write_chunk(n, self._summaries[lo : hi + 1], frames)

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

    def _base(self, s, k: int) -> int:
        """Step of the nearest snapshot at or before ``k`` session ``s`` can restore (the shown one may borrow the run-ahead's)."""
        base = max(j for j in s.snapshot_steps if j <= k)
        if s is self.session and self._ahead is not None:
            base = max([base] + [j for j in self._ahead.snapshot_steps if j <= k])
        return max(base, self._disk_base(k))

    def _restore_for(self, s, k: int) -> None:
        """Put session ``s`` at or before step ``k`` through the nearest snapshot it can restore, in memory or on
        disk (an unreadable disk snapshot is dropped and the next nearest used). The run-ahead only ever moves on."""
        base = self._base(s, k)
        if s is self._ahead and base <= s.step_count:
            return
        if base not in s.snapshot_steps:
            if self._ahead is not None and s is not self._ahead and base in self._ahead.snapshot_steps:
                share_snapshot(self._ahead, s, base)
            elif not self._adopt_disk(s, base):
                return self._restore_for(s, k)
        t0 = time.perf_counter()
        s.restore_snapshot(base)
        if s is self._ahead and self.disk is not None and self.disk.config.snapshots:
            start_journals(s.tracker)  # the segments before ``base`` are on disk already
        if base > 0:
            per = (time.perf_counter() - t0) / base
            self._restore_s_per_step = per if not self._restore_s_per_step else 0.7 * self._restore_s_per_step + 0.3 * per

    def _forward_is_cheaper(self, s, k: int) -> bool:
        """Whether session ``s`` (at or before step ``k``) should step forward rather than restore its nearest snapshot."""
        plain = self._step_s["plain"] or 0.01
        base = self._base(s, k)
        in_memory = base in s.snapshot_steps or (self._ahead is not None and base in self._ahead.snapshot_steps)
        first = base * (self._restore_s_per_step or 0.3 * plain) if in_memory else self._disk_restore_cost_s()
        restore = first + (k - base + 1) * plain
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
            if s.step_count > k or (s is self.session and not self._forward_is_cheaper(s, k)) or (
                    s is ahead and self._disk_jump(k, s.step_count) > 0):
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
        # Through the session's schedule: after a long event gap the updates are no longer t0 + k * dt.
        return max(self.session.steps_until(t_us), 1) - 1

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

    # ------------------------------------------------------------------ catch-up (seeks past what is computed)
    def _target(self, t_us: int, exact: bool) -> int:
        """Step a seek to ``t_us`` lands on: exactly its step, or (``seek_near``) the grid step at or before it."""
        k = self._index_at(t_us)
        return k if exact else k - k % self.cache.every

    def _start_for(self, k: int):
        """The session that reaches step ``k`` soonest by stepping forward, and the step it would start from
        (its position, or a snapshot it can restore). The run-ahead unless the shown session is more than a
        snapshot interval nearer: what the run-ahead computes is kept (snapshots, summaries), the other's is not."""
        ahead, s = self._ahead, self.session
        best = (ahead, ahead.step_count) if ahead is not None and ahead.step_count <= k else (None, -1)
        if best[0] is not None and (d := self._disk_jump(k, best[1])) > 0:
            best = (ahead, d)  # the run-ahead jumps to the disk snapshot
        start = max(s.step_count if s.step_count <= k else -1, self._base(s, k))
        margin = self._snapshot_spacing if best[0] is not None else 0
        return (s, start) if start > best[1] + margin else best

    def catch_up_steps(self, t_us: int, exact: bool = False) -> int:
        k = self._target(t_us, exact)
        if k in self.cache:
            return 0
        return max(0, k - self._start_for(k)[1])

    def catch_up(self, t_us: int, budget_steps: int, exact: bool = False) -> bool:
        """Step towards the seek target plainly: no debug products, no kept frames, no per-step display; only
        the run-ahead's snapshots and the summaries. The seek itself then computes the target step with its
        debug products, so what is shown equals a headless run. The grid frames passed are filled in later
        (:meth:`_backfill`). A disk snapshot the run-ahead jumps to is restored in slices as well (one file's fusion
        journal per call). True once the seek answers with at most that one step."""
        k = self._target(t_us, exact)
        if k in self.cache:
            return True
        if self._ahead is None:
            self._ahead = self._new_ahead()
        s, start = self._start_for(k)
        if s is self._ahead and start > s.step_count and start not in s.snapshot_steps and not self._disk_restore_slice(s, start):
            return False  # a slice of the disk restore (a file's fusion journal replayed; None: unreadable, replanned)
        if s.step_count != start:
            self._restore_for(s, k)
        for _ in range(max(int(budget_steps), 1)):
            if s.step_count >= k or s.done:
                break
            self._advance(s, debug=False, fill=False)
        return s.step_count >= k or s.done

    def preview(self, t_us: int, exact: bool = False) -> Frame | None:
        """The target step's SP-TS images, noise-filter split and a whole-image TDF, rebuilt from the last second or
        so of events (:func:`evpose.tracker.front_end_view.front_end_at`; equal to the tracker's, tested): a few
        milliseconds however far the step is. No pose: that needs every step before it."""
        from evpose.tracker.front_end_view import front_end_at

        k = self._target(t_us, exact)
        t0 = time.perf_counter()
        v = front_end_at(self.session, k)
        ms = (time.perf_counter() - t0) * 1e3
        note = ("the time surfaces are the tracker's own at this step" if v.exact else
                "time surfaces without the ego-motion filter (it needs the pose)")
        return Frame(index=k, t_us=v.t_us, ts_positive=v.ts_positive, ts_negative=v.ts_negative, tdf=v.tdf,
                     events_kept=v.events_kept, events_removed=v.events_removed, status="computing",
                     reason=f"pose being computed (tracking is causal); {note}, the TDF covers the whole image",
                     timings_ms={"preview": ms}, counts={"events_in": len(v.events_kept) + len(v.events_removed),
                                                         "events_kept": len(v.events_kept)}, preview=True)

    def catch_up_progress(self, t_us: int, exact: bool = False) -> tuple[float, float]:
        k = self._target(t_us, exact)
        s = self.session
        reached = s.time_of(max(self._start_for(k)[1], 0))
        return (reached - self.t_start_us) / 1e6, (s.time_of(k + 1) - self.t_start_us) / 1e6

    def play_step(self, stride: int) -> Frame | None:
        """The next frame for playback, at most ``stride`` steps after the shown one (kept frames first)."""
        k0 = self._shown + 1
        last = self.n_steps - 1
        if k0 > last:
            return None
        hi = min(self._shown + max(int(stride), 1), last)
        # The kept frame furthest within the stride; else (a stride shorter than the grid) the next kept one.
        hit = self.cache.latest_at_or_before(hi, k0) or self.cache.next_at_or_after(hi, min(hi + self.cache.every - 1, last))
        if hit is not None:
            self._shown = hit.index
            return hit
        # Nothing kept there: compute a grid step (it is then kept), the furthest within the stride or the next one.
        g = hi - hi % self.cache.every
        if g < k0:
            g = min(k0 + (-k0) % self.cache.every, last)
        return self._produce(g)

    def prefetch(self, budget_steps: int = 5) -> bool:
        """Run the run-ahead session ``budget_steps`` further; False once it has reached the end.

        The shown session and the shown step are untouched.
        """
        if self._ahead is None:
            self._ahead = self._new_ahead()
        s = self._ahead
        if self.disk is not None and self._flush_disk_snapshot(block=s.done):
            return True  # one queued disk snapshot per call: a command waits at most one write (and at the end its encoding)
        if s.done:
            return self._backfill(budget_steps)
        if s.step_count < self._disk_steps:
            # Steps read from disk are only recomputed for their snapshots: one at a time, so a command waits one step.
            budget_steps = 1
        for _ in range(max(int(budget_steps), 1)):
            if s.done:
                break
            self._advance(s, debug=False)
        return not s.done or bool(self._unkept)

    def _backfill(self, budget_steps: int) -> bool:
        """Once the run-ahead is done: the shown session recomputes the grid frames a catch-up skipped (from the
        snapshot before the first), at most ``budget_steps`` steps; False when none are left.

        Seeks there were already exact and quick (a restore and a few steps); this is for smooth playback
        through the gap and for the disk cache, whose chunks wait for their frames."""
        if not self._unkept:
            return False
        k = min(self._unkept)
        s = self.session
        if s.step_count > k or self._base(s, k) > s.step_count:
            self._restore_for(s, k)
        for _ in range(max(int(budget_steps), 1)):
            i = s.step_count
            if not self._unkept or s.done:
                break
            self._advance(s, debug=i in self._unkept)
            self._unkept.discard(i)  # kept, or dropped by the frame budget at once: either way done
            if self.disk is not None:
                self._write_chunk_if_ready(i // self.disk.chunk_steps)
            if self._unkept and min(self._unkept) - s.step_count > self._snapshot_spacing:
                break  # the next one is nearer a snapshot: restore there next slice
        return bool(self._unkept)

