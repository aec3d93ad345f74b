"""A far seek being computed in slices by the player (see ``Player._seek``): its target, progress and cost.

Tracking is causal, so the state at ``t`` needs every step before ``t``. When a
seek lands past what the engine has computed, the player asks the engine for
those steps a slice at a time (``Engine.catch_up``), hearing commands in
between, and shows the seek's frame once they are done. :class:`Seeking` is that part of the player
(app/player.py), split out of it in session 29 with no behaviour changed (the player had grown past 500 lines).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.frame import Frame


@dataclass
class CatchUp:
    """A seek whose target is being computed in slices."""

    t_us: int
    """Asked time, microseconds."""
    exact: bool
    """Exactly that step (else the kept-frame grid step at or before it)."""
    steps: int
    """Steps that were left to compute when it started."""
    progress: tuple[float, float] = (0.0, 0.0)
    """(media seconds reached, media seconds of the target) from the recording's start, seconds."""
    cpu_s: float = 0.0
    """Thread CPU spent on it so far, seconds."""
    wall0: float = field(default_factory=time.perf_counter)
    """When it was asked for (``time.perf_counter``), seconds."""
    preview_s: float | None = None
    """Seconds from the ask until the preview (``Engine.preview``) was drawn; None without one."""

    def report(self, outcome: str) -> dict:
        return {"t_us": self.t_us, "steps": self.steps, "wall_s": time.perf_counter() - self.wall0,
                "cpu_s": self.cpu_s, "preview_s": self.preview_s, "outcome": outcome}


class Seeking:
    """The player's seeks (mixed into app.player.Player, whose worker thread alone calls these): at once when little
    is left to compute, else a :class:`CatchUp` advanced a slice per turn of the worker loop.

    Uses the player's ``engine``, ``pc`` (PlayerConfig), ``_catch_up``, ``last_catch_up``, ``last_seek_ms``,
    ``_last_progress``, ``_prefetching``, ``_last_advance_wall`` and its ``_publish``, ``_reanchor``, ``_failed``,
    ``_progress`` and ``_on_error``.
    """

    def _timed_seek(self, t_us: int, exact: bool = False) -> Frame | None:
        t0 = time.perf_counter()
        frame = self.engine.seek(t_us) if exact or not self.pc.snap_seeks else self.engine.seek_near(t_us)
        self.last_seek_ms = (time.perf_counter() - t0) * 1e3
        return frame

    def _seek(self, t_us: int, exact: bool = False) -> None:
        """Show the step at ``t_us``: at once when little is left to compute, else start a catch-up (sliced)."""
        exact = exact or not self.pc.snap_seeks
        self._catch_up = None
        if self.engine.catch_up_cost_steps(t_us, exact) <= self.pc.catch_up_steps:
            self._publish(self._timed_seek(t_us, exact))
            self._reanchor()
            return
        self._catch_up = CatchUp(int(t_us), exact, self.engine.catch_up_steps(t_us, exact))
        self._catch_up.progress = self.engine.catch_up_progress(t_us, exact)
        self._last_progress = 0.0
        if self.pc.preview_seeks:
            try:
                preview = self.engine.preview(t_us, exact)
            except Exception as exc:  # the catch-up goes on without it
                preview = None
                self._on_error(f"seek preview failed: {exc!r}")
            if preview is not None:
                self._publish(preview)
                self._catch_up.preview_s = time.perf_counter() - self._catch_up.wall0

    def _end_catch_up(self, reason: str) -> None:
        c, self._catch_up = self._catch_up, None
        if c is not None:
            self.last_catch_up = c.report(reason)

    def _catch_up_slice(self) -> None:
        """One slice of the catch-up; the seek's frame once it is reached."""
        c = self._catch_up
        c0 = time.thread_time()
        try:
            done = self.engine.catch_up(c.t_us, self.pc.catch_up_steps, c.exact)
        except Exception as exc:
            self._end_catch_up("failed")
            self._failed(f"seek failed: {exc}")
            return
        c.cpu_s += time.thread_time() - c0
        c.progress = self.engine.catch_up_progress(c.t_us, c.exact)
        if done:
            c1 = time.thread_time()
            frame = self._timed_seek(c.t_us, c.exact)
            c.cpu_s += time.thread_time() - c1
            self._end_catch_up("done")
            self.last_seek_ms = self.last_catch_up["wall_s"] * 1e3
            self._prefetching = self.pc.prefetch
            self._publish(frame)
            self._last_advance_wall = None
            self._reanchor()
            return
        now = time.monotonic()
        if now - self._last_progress >= self.pc.progress_every_s:
            self._last_progress = now
            self._progress()
