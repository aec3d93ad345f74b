"""Playback: one engine thread, a play/pause state machine, real-time pacing and coalesced reconfiguration.

Every browser tab sends commands into one queue; only the worker thread
touches the engine, so several tabs cannot corrupt its state (they all see the
same session, like viewers of one shared player). Frames are handed to
``on_frame`` from the worker thread, at most ``max_ui_fps`` times a second
while playing, always after a step, seek or reconfiguration. While playing, the
engine is asked for one frame per publish interval (``Engine.play_step``): an
engine with a run-ahead reads it back, otherwise it computes it; every step is
still computed, by the run-ahead or live, so the state shown is always the
headless run's. When frames must be computed, the stride shrinks to keep the
frame rate up and the real-time factor shown says the speed achieved.

A seek past what the engine has computed (tracking is causal: the state at t
needs every step before it) is a *catch-up*: the engine computes the steps
plainly, a slice at a time (``Engine.catch_up``), the status line says how far
it is, commands are heard between slices (a new seek replaces the target;
pause, a step or a new recording cancels it), and only the target's frame is
drawn (the seeks are app/catch_up.py's ``Seeking``, a part of the player). A stretch of the recording without events is gone over at once, not in
real time (app/quiet_stretches.py).
"""

from __future__ import annotations

import queue
import threading
import time
from concurrent.futures import Future
from typing import Callable

from app.catch_up import CatchUp, Seeking
from app.engine import Engine
from app.frame import Frame
from app.player_config import PlayerConfig, PlayState, RerunFrom
from app.quiet_stretches import QuietStretches

__all__ = ["Player", "PlayerConfig", "PlayState", "RerunFrom"]


EngineFactory = Callable[[object], Engine]
"""Builds an engine from a configuration (None = the engine's defaults)."""


class Player(Seeking):
    """Owns the engine and the thread that drives it."""

    def __init__(self, factory: EngineFactory, on_frame: Callable[[Frame, Engine], None], config=None,
                 player_config: PlayerConfig | None = None, on_error: Callable[[str], None] | None = None,
                 on_engine: Callable[[Engine], None] | None = None, on_progress: Callable[[Engine], None] | None = None):
        self.pc = player_config or PlayerConfig()
        self._on_frame = on_frame
        self._on_error = on_error or (lambda msg: None)
        self._on_engine = on_engine or (lambda engine: None)
        """Called (worker thread) whenever the engine is replaced: new recording or new configuration."""
        self._on_progress = on_progress or (lambda engine: None)
        """Called (worker thread) about once a second while the engine runs ahead with nothing new shown."""
        self._last_progress = 0.0
        self._queue: queue.Queue = queue.Queue()
        self._lock = threading.Lock()
        self._pending: tuple[object, RerunFrom] | None = None
        self._pending_deadline = 0.0
        self.state = PlayState.PAUSED
        self.speed = 1.0
        self.loop = False
        self.config_applies = 0
        """How many times a configuration change rebuilt the engine (coalescing makes this small)."""
        self.last_seek_ms = 0.0
        self.last_frame: Frame | None = None
        self._factory = factory
        self.engine: Engine = factory(config)
        self._ready: Frame | None = None
        self._ready_stride = 1
        self._step_wall_s = 0.0
        """Wall seconds per step of the last playback frame when it had to be computed (0: it was at hand)."""
        self._anchor = (0.0, 0)
        self._last_publish = 0.0
        self._draw_s = 0.0
        self._unpublished: Frame | None = None
        self._play_stats = [0.0, 0]
        """Wall seconds and media microseconds of the current (or last) play, since play was pressed."""
        self._last_advance_wall: float | None = None
        self._ended_at: float | None = None
        """When playback last stopped by itself at the end (monotonic seconds; None after any other command)."""
        self.quiet = QuietStretches()
        """Stretches without events playback goes over at once (app/quiet_stretches.py)."""
        self._prefetching = self.pc.prefetch
        self._catch_up: CatchUp | None = None
        """The seek being computed in slices, if any."""
        self.last_catch_up: dict = {}
        """The last catch-up: target, steps, wall and thread CPU seconds, and whether it finished or was cancelled."""
        self.computing = False
        """The worker thread is in a command or a slice of work, which commands queue behind (a first step loads the
        compiled kernels: 0.3 s, a minute or more on a cold numba cache, and cannot be interrupted)."""
        self._thread = threading.Thread(target=self._run, name="evpose-player", daemon=True)
        self._running = True
        self._thread.start()

    # ----- commands (any thread) -----
    def play(self) -> None:
        self._queue.put(("play",))

    def pause(self) -> None:
        self._queue.put(("pause",))

    def toggle(self) -> None:
        self._queue.put(("toggle",))

    def step_forward(self) -> None:
        self._queue.put(("step", 1))

    def step_back(self) -> None:
        self._queue.put(("step", -1))

    def seek(self, t_us: int, exact: bool = False) -> None:
        """Show the step at ``t_us``; ``exact``: that very step, never a kept frame before it (PlayerConfig.snap_seeks)."""
        self._queue.put(("seek", int(t_us), bool(exact)))

    def set_speed(self, speed: float) -> None:
        self._queue.put(("speed", float(min(10.0, max(0.1, speed)))))

    def set_loop(self, loop: bool) -> None:
        self._queue.put(("loop", bool(loop)))

    def set_config(self, config, rerun: RerunFrom = RerunFrom.CURRENT) -> None:
        """Ask for a rebuild with ``config``; calls within ``coalesce_s`` of each other collapse into one."""
        with self._lock:
            self._pending = (config, RerunFrom(rerun))
            self._pending_deadline = time.monotonic() + self.pc.coalesce_s
        self._queue.put(("wake",))

    def load(self, factory: EngineFactory, config=None) -> None:
        """Switch to another recording/map without restarting the server."""
        self._queue.put(("load", factory, config))

    def call(self, fn: Callable[[Engine], object]) -> Future:
        """Run ``fn(engine)`` on the worker thread (safe access to engine state); returns a Future."""
        fut: Future = Future()
        self._queue.put(("call", fn, fut))
        return fut

    def cancel_seek(self) -> None:
        """Stop computing towards a far seek target (the frame shown stays)."""
        self._queue.put(("cancel",))

    def wait_idle(self, timeout: float = 30.0) -> bool:
        """Block until all queued commands, pending changes and seeks being computed are done (tests, exports)."""
        end = time.monotonic() + timeout
        if not (self.call(lambda e: None).result(timeout) is None and self._wait_pending(timeout)):
            return False
        while self.call(lambda e: self._catch_up is not None).result(max(end - time.monotonic(), 0.1)):
            if time.monotonic() > end:
                return False
            time.sleep(0.02)
        return True

    def _wait_pending(self, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self._lock:
                pending = self._pending is not None
            if not pending:
                # The rebuild may still be running on the worker: queue behind it.
                return self.call(lambda e: None).result(timeout) is None
            time.sleep(0.02)
        return False

    def stop(self) -> None:
        self._running = False
        self._queue.put(("stop",))
        self._thread.join(timeout=5.0)

    @property
    def busy(self) -> bool:
        """Playing, computing a seek or running ahead: the worker thread wants a core (the warm-up waits meanwhile)."""
        return self.state == PlayState.PLAYING or self._catch_up is not None or bool(self._prefetching)

    def stats(self) -> dict:
        wall, media = self._play_stats
        f = self.last_frame
        return {
            "state": self.state.value, "speed": self.speed, "loop": self.loop,
            "t_us": f.t_us if f else None, "index": f.index if f else None,
            "real_time_factor": (media / 1e6) / wall if wall > 0 else 0.0,
            "config_applies": self.config_applies, "last_seek_ms": self.last_seek_ms,
            "catching_up": c.progress if (c := self._catch_up) is not None else None,
            "skipped_gap": self.quiet.skipped,
        }

    # ----- worker thread -----
    def _publish(self, frame: Frame | None, force: bool = True) -> None:
        if frame is None:
            return
        if not frame.preview:
            # A preview is drawn but the engine is not there yet: steps, pause and cancels go on from the last real frame.
            self.last_frame = frame
        now = time.monotonic()
        # While playing, drawing may take at most ~1/(1+draw_share_factor) of the time: slow draws lower the frame rate.
        interval = max(1.0 / self.pc.max_ui_fps, self.pc.draw_share_factor * self._draw_s)
        if not force and now - self._last_publish < interval:
            self._unpublished = frame
            return
        self._unpublished = None
        self._last_publish = now
        try:
            self._on_frame(frame, self.engine)
        except Exception as exc:  # a drawing bug must not kill playback
            self._on_error(f"display failed: {exc!r}")
        self._draw_s = time.monotonic() - now

    def _flush_unpublished(self) -> None:
        if self._unpublished is not None:
            self._publish(self._unpublished)

    def _reanchor(self) -> None:
        t = self.last_frame.t_us if self.last_frame else self.engine.t_start_us
        self._anchor = (time.monotonic(), t)

    def _failed(self, message: str) -> None:
        """Pause after a failed step or seek, with every tab redrawn at the step still shown (a failed far seek left
        its preview's "computing 0.0 / 0.3 s ... pause to cancel" up, a failed play step "playing at 1.0x"), then say why."""
        self.state = PlayState.PAUSED
        self._ready = self._unpublished = None
        self._publish(self.last_frame)
        self._on_error(message)

    def _progress(self) -> None:
        try:
            self._on_progress(self.engine)
        except Exception as exc:  # a status-line bug must not stop the computation
            self._on_error(f"progress display failed: {exc!r}")

    def _handle(self, cmd: tuple) -> None:
        kind = cmd[0]
        if kind in ("seek", "load"):
            self._ready = None
        if kind in ("seek", "load", "step", "play", "toggle"):
            self.quiet.reset()
        if self._catch_up is not None and kind in ("seek", "load", "step", "pause", "cancel") or (
                kind == "toggle" and self._catch_up is not None and self.state == PlayState.PLAYING):
            # A new seek replaces the target; a step, pause or new recording gives it up (what was computed stays).
            self._end_catch_up("replaced" if kind == "seek" else "cancelled")
            if kind != "seek":
                self._progress()
            if kind == "cancel":
                self._publish(self.last_frame)  # every tab's time slider back to the step shown
        ended_at = self._ended_at
        if kind not in ("speed", "loop", "call"):
            self._ended_at = None
        if kind == "toggle" and self.state == PlayState.PAUSED and ended_at is not None and (
                time.monotonic() - ended_at < self.pc.late_pause_s):
            return  # the pause pressed while the page still showed playback, arriving after the end (PlayerConfig.late_pause_s)
        if kind == "play" or (kind == "toggle" and self.state == PlayState.PAUSED):
            # At the last step (by count: it lies before the last event), play starts again instead of doing nothing.
            if self.last_frame is None or self.engine.current_t_us >= self.engine.t_end_us or self.engine.is_last(self.last_frame):
                self._publish(self._timed_seek(self.engine.t_start_us) if self.last_frame else self.engine.step())
            self.state = PlayState.PLAYING
            self._last_advance_wall = None
            self._play_stats = [0.0, 0]  # the real-time factor shown is this play's
            self._reanchor()
        elif kind == "pause" or kind == "toggle":
            self.state = PlayState.PAUSED
            if self._ready is not None:
                self._unpublished = self._ready
                self._ready = None
            # Redraw once so every tab shows the paused state and the latest step.
            self._publish(self._unpublished if self._unpublished is not None else self.last_frame)
        elif kind == "step":
            self.state = PlayState.PAUSED
            self._flush_unpublished()
            if cmd[1] > 0:
                nxt = (self.last_frame.index + 1) if self.last_frame is not None else 0
                if self._ready is not None and self._ready.index == nxt:
                    frame = self._ready  # computed ahead for playback and exactly the next step
                elif self._ready is not None or self.last_frame is not None:
                    # Playback frames may lie several steps on: go to exactly the one after the shown step.
                    frame = self.engine.seek_step(nxt)
                else:
                    frame = self.engine.step()
            else:
                current = self.last_frame.index if self.last_frame else 0
                frame = self.engine.seek_step(max(0, current - 1))
            self._ready = None
            self._publish(frame if frame is not None else self.last_frame)
        elif kind == "seek":
            self._seek(cmd[1], cmd[2])
            self._last_advance_wall = None
        elif kind == "speed":
            self.speed = cmd[1]
            self._reanchor()
            if self.state == PlayState.PAUSED:
                # Nothing is drawn until play: the status line said "paused at 1.0x" after the speed was set to 3.
                self._progress()
        elif kind == "loop":
            self.loop = cmd[1]
        elif kind == "load":
            self.state = PlayState.PAUSED
            old, self.engine = self.engine, cmd[1](cmd[2])
            old.release()
            self._factory = cmd[1]
            self.last_frame = None
            self._play_stats = [0.0, 0]
            self._prefetching = self.pc.prefetch
            self._on_engine(self.engine)
            self._publish(self.engine.step())
        elif kind == "call":
            try:
                cmd[2].set_result(cmd[1](self.engine))
            except Exception as exc:
                cmd[2].set_exception(exc)

    def _apply_pending(self) -> None:
        with self._lock:
            config, rerun = self._pending
            self._pending = None
        t_now = self.last_frame.t_us if self.last_frame else None
        self._ready = None
        try:
            engine = self._factory(config)
        except Exception as exc:
            self._on_error(f"configuration rejected: {exc}")
            return
        self.engine, old = engine, self.engine
        old.release()
        self._prefetching = self.pc.prefetch
        self.config_applies += 1
        self._on_engine(engine)
        self._end_catch_up("replaced")
        if rerun == RerunFrom.START or t_now is None:
            self._publish(self.engine.step())
            self._reanchor()
        else:
            self._seek(t_now, exact=True)

    def _timeout(self) -> float | None:
        waits = []
        with self._lock:
            if self._pending is not None:
                waits.append(self._pending_deadline - time.monotonic())
        if self._catch_up is not None:
            waits.append(0.0)
        elif self.state == PlayState.PLAYING:
            if self._ready is None or (self._prefetching and self.pc.prefetch_while_playing):
                waits.append(0.0)
            else:
                waits.append(self._due(self._ready) - time.monotonic())
        elif self._prefetching:
            waits.append(0.0)
        return max(0.0, min(waits)) if waits else None

    def _due(self, frame: Frame) -> float:
        wall0, media0 = self._anchor
        return wall0 + (frame.t_us - media0) / 1e6 / self.speed

    def _run(self) -> None:
        while self._running:
            self.computing = False
            try:
                cmd = self._queue.get(timeout=self._timeout())
            except queue.Empty:
                cmd = None
            self.computing = True
            if cmd is not None:
                if cmd[0] == "stop":
                    break
                try:
                    self._handle(cmd)
                except Exception as exc:
                    self._failed(f"{cmd[0]} failed: {exc}")
                continue
            with self._lock:
                due_config = self._pending is not None and time.monotonic() >= self._pending_deadline
            if due_config:
                self._apply_pending()
                continue
            if self._catch_up is not None:
                self._catch_up_slice()
            elif self.state == PlayState.PLAYING:
                self._advance()
            elif self._prefetching:
                self._prefetch_slice(self.pc.prefetch_steps)

    def _stride(self) -> int:
        """Steps between two displayed frames at the current speed: one frame per publish interval of media time."""
        step_us = getattr(self.engine, "step_us", None)
        if not step_us:
            return 1
        interval = max(1.0 / self.pc.max_ui_fps, self.pc.draw_share_factor * self._draw_s)
        stride = max(1, int(self.speed * interval * 1e6 // step_us))
        quiet = self.last_frame is not None and self.quiet.quiet_for_us(self.last_frame.t_us) > self.pc.skip_gaps_s * 1e6
        if quiet and getattr(self.engine, "play_stops_at_events", False):
            # Gone over at once (SLAM steps through it, 0.7 ms a step, 13 ms a drawn frame): a frame per skip_gaps_s
            # of it, not per publish interval. The engine stops its stride where events come again.
            return max(stride, int(self.pc.skip_gaps_s * 1e6 // step_us))
        if self._step_wall_s > 0:
            # Computing steps live (slower than real time): fewer steps per frame keep the frame rate up.
            stride = min(stride, max(1, int(interval / self._step_wall_s)))
        return stride

    def _prefetch_slice(self, steps: int) -> None:
        try:
            self._prefetching = self.engine.prefetch(steps)
        except Exception as exc:
            self._prefetching = False
            self._on_error(f"prefetch failed: {exc}")
        now = time.monotonic()
        if self.state == PlayState.PAUSED and (now - self._last_progress >= 1.0 or not self._prefetching):
            self._last_progress = now
            self._progress()

    def _advance(self) -> None:
        if self._ready is None:
            try:
                stride = self._stride()
                before = self.last_frame.index if self.last_frame is not None else -1
                t0 = time.monotonic()
                self._ready = self.engine.play_step(stride)
                self._ready_stride = stride
                took = time.monotonic() - t0
                steps = (self._ready.index - before) if self._ready is not None else 0
                # Wall time per step when frames are computed, not read back (then the speed is the limit).
                self._step_wall_s = took / steps if steps > 0 and took > 0.5 / self.pc.max_ui_fps else 0.0
            except Exception as exc:
                self._failed(f"step failed: {exc}")
                return
            if self._ready is None:
                if self.loop:
                    self._flush_unpublished()
                    self._publish(self._timed_seek(self.engine.t_start_us))
                    self._reanchor()
                else:
                    # The end: drawn once more, paused, or every tab's status line would still say "playing".
                    self.state = PlayState.PAUSED
                    self._ended_at = time.monotonic()
                    self._publish(self._unpublished if self._unpublished is not None else self.last_frame)
                return
        now = time.monotonic()
        gap = self.quiet.ending_at(self._ready, self.last_frame, getattr(self.engine, "step_us", None),
                                   self.pc.skip_gaps_s * 1e6)
        if gap is not None:
            # No events since the frame shown for longer than skip_gaps_s: shown now, paced from here on.
            self.quiet.went_over(gap)
            self._anchor = (now, self._ready.t_us)
            self._last_advance_wall = None  # nor counted in the real-time factor
        due = self._due(self._ready)
        if now < due:
            if self._prefetching and self.pc.prefetch_while_playing:
                # The next frame is ready early: run ahead one step (a few ms) instead of sleeping.
                self._prefetch_slice(1)
            return
        if now - due > self.pc.max_lag_s:
            self._reanchor()
        prev_t = self.last_frame.t_us if self.last_frame else self._ready.t_us
        frame, self._ready = self._ready, None
        wall_prev = self._last_advance_wall
        if wall_prev is not None:
            self._play_stats[0] += now - wall_prev
            self._play_stats[1] += frame.t_us - prev_t
        self._last_advance_wall = now
        # Frames already spaced by the publish interval are all drawn; single steps are thinned to it.
        self._publish(frame, force=self._ready_stride > 1)
