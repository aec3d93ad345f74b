"""The warm-up: recordings are prepared before they are opened, the way video editors build proxies.

Tracking is causal, so the pose of a far seek in a recording nobody has opened
needs every step before it (3.5-7.7 s for 9.5 s into the 10 s demo). On
``evpose app`` start (and on each rescan of the data folders) a background
process computes, for every recording the browser lists, the pairing it opens
by default (the map :func:`~app.browser.guess_map_for` picks, tracking mode,
the default configuration) into the disk cache (``app/disk_cache.py``): the
run-ahead of a fresh :class:`~app.tracker_engine.TrackerEngine` stepped to the
end, so the entry holds exactly the chunks the player's own run-ahead writes
and a later opening's far seek reads its frame from disk.

- One process (``multiprocessing`` "spawn": the server's threads are not
  forked) at the lowest CPU priority (``os.nice(19)``): it only gets a core the
  UI and the player leave idle. One recording at a time, in browser order.
  While the player plays, computes a far seek or runs ahead it holds still
  altogether (at nice 19 alone it took 1-7 % of the tracker's steps when both
  wanted a core, and delayed the open recording's run-ahead).
- Entries already complete are skipped (the engine reads them back and finds
  every step there).
- The recording open in the viewer is left to the player's run-ahead, which
  writes the same entry: the warm-up defers it (and leaves it if it was on it)
  until another one is opened. Two writers of one entry could not corrupt it
  anyway: every chunk is written atomically (temporary file, rename) with the
  same contents (the tracker is deterministic).
- A recording that cannot be read is reported ("failed: reason") and skipped;
  the warm-up goes on with the next.
- No new recording is started once the cache holds :data:`FULL_SHARE` of its
  budget, so preparing never pushes out entries of recordings that were watched.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import queue
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from app.browser import DataEntry, EntryKind

OPEN_NOTE = "open in the viewer: its run-ahead prepares it"
PREPARED = "prepared"
FULL_SHARE = 0.8
"""The warm-up starts no new recording once the cache folder holds this share of its budget: the cache drops the
least recently used entries to fit, and prepared recordings nobody opened must not push out what was watched."""


def cache_bytes(folder: Path) -> int:
    """Bytes of every file in the cache folder's entries."""
    folder = Path(folder)
    return sum(f.stat().st_size for d in folder.iterdir() if d.is_dir() for f in d.iterdir() if f.is_file()) \
        if folder.is_dir() else 0


@dataclass
class PrepareResult:
    """What :func:`prepare_pair` did."""

    steps: int
    """Steps of the recording."""
    computed: bool
    """Whether the steps were computed now (False: the entry was complete already)."""
    seconds: float
    """Wall time, seconds."""
    complete: bool
    """Every chunk of the entry is on disk (False: stopped before the end)."""


def prepare_pair(recording, contour_map, paths: tuple[Path, Path], disk, frames=None,
                 on_progress: Callable[[float], None] | None = None, keep_going: Callable[[], bool] | None = None,
                 slice_steps: int = 25, acquire_s: float = 0.0) -> PrepareResult:
    """Fill the disk cache entry of ``recording`` tracked against ``contour_map`` with the default configuration, as
    the viewer opens it (``paths``: their files, which the entry is keyed by; ``frames``: the viewer's frame cache
    settings). ``on_progress(fraction)`` after each slice of ``slice_steps`` steps; ``keep_going()`` False stops.
    ``acquire_s > 0``: raise :class:`InputError` naming the map, as ``evpose track --acquire-s`` does, when no
    update registers within that many seconds (:mod:`evpose.tracker.map_acquisition`); the steps computed until
    then stay in the cache. 0 (the warm-up's): never (the viewer shows such a pairing, with a warning)."""
    from app.engine_factory import engine_factory
    from app.tracker_engine import TrackerEngine
    from evpose.errors import InputError
    from evpose.tracker.map_acquisition import chance_mismatch, chance_problem, map_mismatch, mismatch_problem

    def check_map(engine, finished: bool) -> None:
        known = engine.known_summaries
        steps = [(h.t_us, h.counts) for h in known]
        s = map_mismatch(steps, engine.session.t0_us, acquire_s, finished)
        z = None if s is not None else chance_mismatch(steps, engine.session.t0_us, acquire_s, finished)
        if s is not None or z is not None:
            engine.flush_disk_snapshots()
            problem = (mismatch_problem(s, paths[0].name) if s is not None else
                       chance_problem(z, min(acquire_s, (steps[-1][0] - engine.session.t0_us) / 1e6), paths[0].name))
            raise InputError(paths[1], problem, f"updates 1-{len(known)}")

    t0 = time.perf_counter()
    engine = engine_factory(recording, contour_map, "tracking", frames, disk, paths)(None)
    if not isinstance(engine, TrackerEngine):
        cause = getattr(engine, "cause", None)
        if isinstance(cause, InputError):  # its record and problem, without the explanation's repeat of the path
            from evpose.tracker.session import MapOutOfViewError

            # A map out of view names the map, as `evpose track` and `refine-map` do: the likelier culprit.
            culprit = paths[1] if isinstance(cause, MapOutOfViewError) else paths[0]
            raise InputError(culprit, f"tracking cannot start: {cause.problem}", cause.record)
        raise InputError(paths[0], engine.explanation or "cannot be tracked")
    if engine.disk is None:
        raise InputError(None, "the disk cache is off: there is nothing to prepare into")
    n = engine.n_steps
    if engine.disk_steps >= n:
        check_map(engine, True)
        return PrepareResult(n, False, time.perf_counter() - t0, True)
    while engine.prefetch(slice_steps):
        if engine.disk.error:
            raise InputError(engine.disk.dir, engine.disk.error)
        check_map(engine, len(engine.known_summaries) >= n)
        if on_progress is not None:
            on_progress(engine.frontier / max(n, 1))
        if keep_going is not None and not keep_going():
            engine.flush_disk_snapshots()  # those taken are encoded by now or soon: keep them
            return PrepareResult(n, True, time.perf_counter() - t0, False)
    if engine.disk.error:
        raise InputError(engine.disk.dir, engine.disk.error)
    check_map(engine, True)
    complete = len(engine.disk.written) == math.ceil(n / engine.disk.chunk_steps)
    return PrepareResult(n, True, time.perf_counter() - t0, complete)


def _worker(jobs: list[DataEntry], maps: list[DataEntry], open_path: Path | None, disk, frames, commands, reports,
            nice: int = 19, hold: bool = False) -> None:
    """The warm-up process: prepare each job's default pairing, reporting ``(label, state)`` on ``reports`` (None
    when done). ``nice``: added to its CPU niceness (19: only the cores the viewer leaves idle; tests run it in-process
    with 0). ``hold``: start held (the viewer is playing); ``("hold", bool)`` commands change it."""
    if threading.current_thread() is threading.main_thread():  # its own process (tests run it in a thread)
        # Ctrl+C reaches the whole process group; the viewer stops this process itself (no traceback on the terminal).
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        os.nice(nice)
    except OSError:
        pass
    from app.browser import guess_map_for, load_map, load_recording

    parent = os.getppid()
    state = {"open": open_path, "stop": False, "hold": bool(hold)}

    def poll() -> bool:
        """Hear the viewer's commands; False once told to stop (or orphaned)."""
        while True:
            try:
                cmd = commands.get_nowait()
            except queue.Empty:
                break
            if cmd[0] == "stop":
                state["stop"] = True
            elif cmd[0] == "open":
                state["open"] = cmd[1]
            elif cmd[0] == "hold":
                state["hold"] = cmd[1]
        if os.getppid() != parent:
            state["stop"] = True
        return not state["stop"]

    def wait_while_held() -> bool:
        """Sleep while the viewer's player wants a core (plays, computes a seek, runs ahead); False once stopped."""
        while poll() and state["hold"]:
            time.sleep(0.2)
        return not state["stop"]

    said: dict[str, str] = {}

    def say(label: str, text: str) -> None:
        if said.get(label) != text:  # the browser's list is redrawn only when something changed
            said[label] = text
            reports.put((label, text))

    pending = list(jobs)
    while pending and wait_while_held():
        for e in pending:
            if e.path == state["open"]:
                say(e.label, OPEN_NOTE)
        ready = [e for e in pending if e.path != state["open"]]
        if not ready:
            time.sleep(0.5)  # only the open recording is left: wait until another is opened
            continue
        entry = ready[0]
        pending.remove(entry)
        last = [-1.0, 0.0]

        def progress(fraction: float, label=entry.label) -> None:
            now = time.monotonic()
            if int(fraction * 100) != int(last[0] * 100) and now - last[1] >= 0.5:
                last[:] = [fraction, now]
                say(label, f"preparing {100 * fraction:.0f} %")

        try:
            if cache_bytes(disk.folder()) >= FULL_SHARE * disk.budget_mb * 2**20:
                say(entry.label, f"not prepared: the disk cache is {100 * FULL_SHARE:.0f} % full "
                                 f"(budget {disk.budget_mb:.0f} MB)")
                continue
            say(entry.label, "preparing 0 %")
            recording = load_recording(entry.path)
            map_entry = guess_map_for(entry, maps, recording.metadata)
            if map_entry is None:
                say(entry.label, "no map found: events only, nothing to prepare")
                continue
            result = prepare_pair(recording, load_map(map_entry.path), (entry.path, map_entry.path), disk, frames,
                                  progress, lambda p=entry.path: wait_while_held() and state["open"] != p)
        except Exception as exc:  # one unreadable recording must not stop the others
            # The record too ("IMU sample 5: NaN ..."): the problem alone did not say where. Not the path: the label is it.
            where = [getattr(exc, "record", None), getattr(exc, "problem", None)]
            say(entry.label, "failed: " + (": ".join(w for w in where if w) if where[1] else str(exc)))
            continue
        if result.complete:
            how = f"computed in {result.seconds:.1f} s" if result.computed else "found in the disk cache"
            say(entry.label, f"{PREPARED} (with `{map_entry.label}`, {how})")
        elif not state["stop"]:
            pending.append(entry)  # opened meanwhile: the player goes on with it; back to it once it is closed
    reports.put(None)


class WarmUp:
    """The viewer's side of the warm-up: starts and stops the process, tells it what is open, shows its progress."""

    def __init__(self, disk, frames, on_status: Callable[[str], None], enabled: bool = True,
                 busy: Callable[[], bool] | None = None):
        self.disk, self.frames = disk, frames
        self._busy = busy
        """Whether the player wants a core (playing, computing a seek, running ahead): the warm-up holds still meanwhile
        (checked every 0.5 s)."""
        self.enabled = bool(enabled and disk is not None and disk.enabled)
        """Off with ``--no-warm-up``, and whenever the disk cache is off (there would be nowhere to write)."""
        self._on_status = on_status
        self._open: Path | None = None
        self._proc = None
        self._commands = self._reports = None
        self._listener: threading.Thread | None = None
        self._lock = threading.Lock()
        self.states: dict[str, str] = {}
        """Recording label -> what the warm-up says of it (queued, preparing 40 %, prepared, failed: ...)."""
        self.finished = threading.Event()
        """Set once the process has gone through every recording (or stopped)."""

    def start(self, entries: list[DataEntry]) -> None:
        """(Re)start on the recordings of a scan (unreadable ones are left out: the browser lists them already)."""
        self.stop()
        jobs = [e for e in entries if e.kind == EntryKind.RECORDING and e.error is None]
        maps = [e for e in entries if e.kind == EntryKind.MAP]
        with self._lock:
            self.states = {e.label: "queued" for e in jobs} if self.enabled else {}
        self.finished = threading.Event()
        if not self.enabled or not jobs:
            self.finished.set()
            self._show()
            return
        ctx = multiprocessing.get_context("spawn")  # forking a process with the server's threads running is unsafe
        self._commands, self._reports = ctx.Queue(), ctx.Queue()
        held = self._is_busy()
        self._proc = ctx.Process(target=_worker, name="evpose-warm-up", daemon=True,
                                 args=(jobs, maps, self._open, self.disk, self.frames, self._commands, self._reports,
                                       19, held))
        self._proc.start()
        self._listener = threading.Thread(target=self._listen, args=(self._proc, self._reports, self.finished, held),
                                          name="warm-up-status", daemon=True)
        self._listener.start()
        self._show()

    def opened(self, recording_path: Path | None) -> None:
        """The recording the viewer has open in tracking mode (None: none): left to the player's run-ahead, which
        writes its entry, until another one is opened."""
        self._open = Path(recording_path).resolve() if recording_path is not None else None
        if self._proc is not None and self._proc.is_alive():
            self._commands.put(("open", self._open))

    def wait(self, timeout: float) -> bool:
        """Block until every recording has been gone through; False on timeout."""
        return self.finished.wait(timeout)

    def stop(self) -> None:
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.is_alive():
            self._commands.put(("stop",))
            proc.join(timeout=5.0)
            if proc.is_alive():  # mid-slice under load: a half-written chunk is only ever a temporary file
                proc.terminate()
                proc.join(timeout=5.0)
        if self._listener is not None:
            self._listener.join(timeout=2.0)

    def _listen(self, proc, reports, finished: threading.Event, held: bool) -> None:
        while True:
            busy = self._is_busy()
            if busy != held and proc.is_alive():
                held = busy
                self._commands.put(("hold", busy))
            try:
                msg = reports.get(timeout=0.5)
            except queue.Empty:
                if proc.is_alive():
                    continue
                msg = None if proc.exitcode == 0 else ("", f"stopped (exit code {proc.exitcode})")
            if msg is None or self._proc is not proc:
                break  # done, or stopped for a rescan (whose new process reports afresh)
            with self._lock:
                if msg[0]:
                    self.states[msg[0]] = msg[1]
                else:
                    self.states = {k: (msg[1] if not v.startswith((PREPARED, "failed", "no map")) else v)
                                   for k, v in self.states.items()}
            self._show()
            if not msg[0]:
                break
        finished.set()

    def _is_busy(self) -> bool:
        try:
            return bool(self._busy()) if self._busy is not None else False
        except Exception:  # a player being replaced: not busy for now, asked again in 0.5 s
            return False

    def markdown(self) -> str:
        """The browser's list of what is prepared for seeking (empty when the warm-up is off)."""
        with self._lock:
            states = dict(self.states)
        if not states:
            return ""
        done = [k for k, v in states.items() if v.startswith(PREPARED) or v == OPEN_NOTE]
        no_map = [k for k, v in states.items() if v.startswith("no map")]
        if len(done) + len(no_map) == len(states):
            # All settled, one line: the list (a line or two per recording) pushed the 3D view, Layout and Export
            # folders below a 900 px screen for good (session 28); what is queued, preparing or failed is listed.
            # "With the map ... and the default parameters": another pairing is not prepared (the list said nothing).
            return (f"**Prepared for seeking:** {len(done)} recording{'s' if len(done) != 1 else ''}, each with the map "
                    "it opens with and the default parameters (a seek anywhere there reads its pose from the disk cache)"
                    + (f"; {len(no_map)} without a map, nothing to prepare" if no_map else "") + ".")
        lines = "\n".join(f"- `{label}`: {state}" for label, state in sorted(states.items()))
        return ("**Prepared for seeking** (computed in the background at the lowest CPU priority; the pose of a seek "
                "anywhere in a prepared recording is read from the disk cache):\n" + lines)

    def _show(self) -> None:
        try:
            self._on_status(self.markdown())
        except Exception:  # a display failure must not stop the warm-up's bookkeeping
            pass
