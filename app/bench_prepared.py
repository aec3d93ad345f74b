"""Benchmarks of the warm-up (``app/warm_up.py``): a far seek in a prepared recording (part of ``far_seek``), a
warm-up kept running in the background while other benchmarks run (``python -m app.bench --background-warm-up R.h5``),
and the tracker's speed with the warm-up running vs paused (``warm_up_interference``)."""

from __future__ import annotations

import os
import shutil
import threading
import time
from pathlib import Path


def _start_warm_up(rec_path: Path, maps_dir: Path, cache_dir: Path, busy=None):
    """The viewer's warm-up process (nice 19) started on this one recording, the maps of ``maps_dir`` to pick from."""
    from app.browser import DataRoots, EntryKind
    from app.disk_cache import DiskCacheConfig
    from app.frame_cache import FrameCacheConfig
    from app.warm_up import WarmUp

    entries = DataRoots(sorted({rec_path.parent.resolve(), Path(maps_dir).resolve()})).scan()
    entries = [e for e in entries if e.kind != EntryKind.RECORDING or e.path == rec_path.resolve()]
    w = WarmUp(DiskCacheConfig(directory=cache_dir), FrameCacheConfig(), lambda md: None, busy=busy)
    w.start(entries)
    return w


def far_seek_prepared(rec_path: Path, map_path: Path, rec, cmap, t_us: int, work_dir: Path) -> dict:
    """Prepare the recording with the viewer's warm-up into an empty cache (timed), then open it in a fresh player
    with that disk cache, as ``evpose app`` does, and seek to ``t_us``: when the frame is drawn."""
    from app.bench import _far_seek_player
    from app.disk_cache import DiskCacheConfig
    from app.engine_factory import engine_factory
    from app.frame_cache import FrameCacheConfig

    cache_dir = Path(work_dir) / "prepared_cache"
    shutil.rmtree(cache_dir, ignore_errors=True)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    w = _start_warm_up(rec_path, map_path.parent, cache_dir)
    w.wait(3600)
    wall = time.perf_counter() - t0
    out = {"warm_up_wall_s": wall, "warm_up_states": dict(w.states),
           "warm_up_loadavg_1min": [load0, os.getloadavg()[0]]}
    factory = engine_factory(rec, cmap, "tracking", FrameCacheConfig(), DiskCacheConfig(directory=cache_dir),
                             (rec_path.resolve(), map_path.resolve()))
    out["player"] = _far_seek_player(rec, cmap, t_us, factory)
    return out


class BackgroundWarmUp:
    """Keeps the viewer's warm-up process busy with ``recordings`` (each with the map the viewer guesses from
    ``maps_dir``) into a throwaway cache, over and over, until closed: the load a warm-up puts on the machine.
    ``busy``: as the viewer's (:class:`~app.warm_up.WarmUp`), when the warm-up is to hold still."""

    def __init__(self, recordings: list[Path], maps_dir: Path, work_dir: Path, busy=None):
        self.busy = busy
        self.recordings, self.maps_dir = [Path(r) for r in recordings], Path(maps_dir)
        self.cache_dir = Path(work_dir) / "background_warm_up_cache"
        self.runs: list[dict] = []
        """One per completed pass over the recordings: wall seconds and what each recording ended as."""
        self.cpu_s = 0.0
        """CPU seconds the warm-up processes used (sampled every 0.5 s, so up to 0.5 s of each one's end is missed)."""
        self.niceness: int | None = None
        self.last_states: dict = {}
        """What the warm-up said when it was stopped (how far the pass under way got)."""
        self._stop = threading.Event()
        self._current = None
        self._thread = threading.Thread(target=self._loop, name="background-warm-up", daemon=True)

    def __enter__(self):
        self._thread.start()
        return self

    def _loop(self) -> None:
        while not self._stop.is_set():
            shutil.rmtree(self.cache_dir, ignore_errors=True)
            t0 = time.perf_counter()
            states = {}
            for rec in self.recordings:
                if self._stop.is_set():
                    return
                self._current = w = _start_warm_up(rec, self.maps_dir, self.cache_dir, self.busy)
                cpu = 0.0
                while not w.wait(0.5) and not self._stop.is_set():
                    cpu = max(cpu, self._sample(w))
                self.cpu_s += cpu
                w.stop()
                states.update(w.states)
                self.last_states = dict(states)
            if not self._stop.is_set():
                self.runs.append({"wall_s": time.perf_counter() - t0, "states": states})

    def _sample(self, w) -> float:
        import psutil

        try:
            proc = psutil.Process(w._proc.pid)
            self.niceness = proc.nice()
            t = proc.cpu_times()
            return t.user + t.system
        except (psutil.Error, AttributeError):
            return 0.0

    def report(self) -> dict:
        return {"completed_passes": self.runs, "cpu_s": self.cpu_s, "niceness": self.niceness,
                "states_when_stopped": self.last_states}

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._current is not None:
            self._current.stop()
        self._thread.join(timeout=3600)
        shutil.rmtree(self.cache_dir, ignore_errors=True)


def bench_warm_up_interference(ctx) -> dict:
    """What the warm-up takes from the viewer: plain tracker steps (the player's run-ahead work) timed in windows of
    wall time while the viewer's warm-up process prepares a recording in the background, alternately running and
    paused (SIGSTOP / SIGCONT), in one run, so a change of the machine's load hits both alike."""
    import signal

    import numpy as np

    from app.bench import demo_pair
    from app.browser import load_map, load_recording
    from evpose.tracker.session import TrackingSession

    rec_path, map_path = demo_pair(Path(ctx.work_dir))
    rec, cmap = load_recording(rec_path), load_map(map_path)
    window_s, pairs = (1.0, 6) if ctx.quick else (1.5, 12)
    session = TrackingSession(rec, cmap)
    session.step()  # numba caches outside the timing
    rates: dict[str, list[float]] = {"running": [], "paused": []}
    shares: dict[str, list[float]] = {"running": [], "paused": []}
    load0 = os.getloadavg()[0]
    with BackgroundWarmUp([rec_path], map_path.parent, Path(ctx.work_dir)) as background:
        time.sleep(3.0)  # the process imports and loads before it computes
        for i in range(2 * pairs):
            phase = "running" if i % 2 == 0 else "paused"
            w = background._current
            pid = w._proc.pid if w is not None and w._proc is not None else None
            if pid is not None and phase == "paused":
                os.kill(pid, signal.SIGSTOP)
            steps, w0, c0 = 0, time.perf_counter(), time.thread_time()
            try:
                while time.perf_counter() - w0 < window_s:
                    if session.step(debug=False) is None:
                        session = TrackingSession(rec, cmap)
                    del session.results[:]
                    steps += 1
            finally:
                if pid is not None and phase == "paused":
                    os.kill(pid, signal.SIGCONT)
            wall = time.perf_counter() - w0
            rates[phase].append(steps / wall)
            shares[phase].append((time.thread_time() - c0) / wall)
    report = background.report()
    out = {"recording": str(rec_path), "window_s": window_s, "windows_each": pairs,
           "loadavg_1min": [load0, os.getloadavg()[0]], "background_warm_up": report}
    for phase in rates:
        out[f"steps_per_s_warm_up_{phase}"] = float(np.mean(rates[phase]))
        out[f"tracker_core_share_warm_up_{phase}"] = float(np.mean(shares[phase]))
    out["steps_per_s_ratio_running_over_paused"] = (out["steps_per_s_warm_up_running"]
                                                    / out["steps_per_s_warm_up_paused"])
    return out
