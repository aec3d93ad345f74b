"""Viewer benchmarks: playback speed with every panel on in a real browser, and seek latency.

Same registry shape as ``evpose/bench/<area>.py`` (``BENCHMARKS = {name: fn(ctx) -> dict}``);
it lives in ``app/`` because ``evpose/`` must not import the viewer. Run it directly:
``python -m app.bench [--full] [--recording R.h5 --map M_map.ply] [--seconds S] [--seeks N]``.
Timings on a shared 2-core machine are noisy; each benchmark reports a headless
baseline measured in the same run.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


DEMO_OVERRIDE: tuple[Path, Path] | None = None
"""(recording, map) given on the command line, used instead of looking for the demo."""
PLAY_SECONDS: float | None = None
"""Wall seconds of each playback phase given on the command line (default: 4 quick, 8 full)."""
N_SEEKS: int | None = None
"""Random seek targets per phase given on the command line (default: 4 quick, 10 full)."""
CURRENT_VIEWER = None
"""The viewer :func:`_viewer` made last (a ``--background-warm-up`` holds still while it plays, as the app's does)."""


def demo_pair(work_dir: Path, seconds: float = 10.0) -> tuple[Path, Path]:
    """The moderate demo (``landing``, 3 m/s) recording and its contour map: bundled ones, else simulated once into ``work_dir``."""
    if DEMO_OVERRIDE is not None:
        return DEMO_OVERRIDE
    for rec in sorted(Path("demo_data").glob("landing*.h5")):
        if rec.stem in ("landing", "landing_moderate"):
            for m in sorted(Path("maps").glob("landing*_map.ply")):
                return rec, m
    work_dir.mkdir(parents=True, exist_ok=True)
    rec, cloud, cmap = work_dir / "landing.h5", work_dir / "landing_cloud.ply", work_dir / "landing_map.ply"
    run = [sys.executable, "-m", "evpose.cli.main"]
    if not rec.exists():
        subprocess.run(run + ["simulate", "--scenario", "landing", "--out", str(rec), "--seconds", str(seconds)], check=True)
    if not cmap.exists():
        subprocess.run(run + ["build-map", str(cloud), "--out", str(cmap)], check=True)
    return rec, cmap


def _cache_dir(work_dir: Path, clear: bool = False) -> Path:
    """The disk cache the benchmark's viewers use (inside ``work_dir``); ``clear`` empties it for a cold start."""
    import shutil

    d = Path(work_dir) / "viewer_cache"
    if clear:
        shutil.rmtree(d, ignore_errors=True)
    return d


def _viewer(rec: Path, cmap: Path, work_dir: Path, prefetch: bool = True):
    """The viewer as ``evpose app`` serves it (run-ahead on unless ``prefetch`` is False), with the pair loaded."""
    from app.disk_cache import DiskCacheConfig
    from app.player import PlayerConfig
    from app.server import AppConfig, ViewerApp

    app = ViewerApp(AppConfig(data=sorted({rec.parent.resolve(), cmap.parent.resolve()}), port=free_port(),
                              export_dir=work_dir / "exports", player=PlayerConfig(prefetch=prefetch),
                              disk_cache=DiskCacheConfig(directory=_cache_dir(work_dir))))
    rec_entry = next(e for e in app.entries if e.path == rec.resolve())
    map_entry = next(e for e in app.entries if e.path == cmap.resolve())
    if not app.select(rec_entry.display, map_entry.display):
        raise RuntimeError(app.rec_info.content)
    global CURRENT_VIEWER
    CURRENT_VIEWER = app
    app.player.wait_idle(120)
    return app


class DrawMeter:
    """Wraps the player's frame callback: counts frames, times each draw (wall and thread CPU), signals each one."""

    def __init__(self, player):
        self.player = player
        self.inner = player._on_frame
        self.wall_ms: list[float] = []
        self.cpu_ms: list[float] = []
        self.drawn = threading.Event()
        self.preview_at: float | None = None
        """``time.perf_counter`` when the last seek preview (``Frame.preview``) was drawn."""
        player._on_frame = self

    def __call__(self, frame, engine) -> None:
        t0, c0 = time.perf_counter(), time.thread_time()
        self.inner(frame, engine)
        self.wall_ms.append((time.perf_counter() - t0) * 1e3)
        self.cpu_ms.append((time.thread_time() - c0) * 1e3)
        if frame.preview:
            self.preview_at = time.perf_counter()
            return
        self.drawn.set()

    def reset(self) -> None:
        self.wall_ms.clear()
        self.cpu_ms.clear()


def _cpu_s() -> tuple[float, float]:
    """CPU seconds used so far by this process and by its children (the browser), for the per-phase load they add."""
    import psutil

    me = psutil.Process()
    kids = 0.0
    for c in me.children(recursive=True):
        try:
            t = c.cpu_times()
            kids += t.user + t.system
        except psutil.Error:
            pass
    t = me.cpu_times()
    return t.user + t.system, kids


def _attach_browser(p, app):
    browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.goto(f"http://127.0.0.1:{app.cfg.port}")
    page.get_by_text("SP-TS positive").first.wait_for(timeout=60_000)
    return browser


def _play(app, meter: DrawMeter, seconds: float) -> dict:
    """Play at 1x from the start for ``seconds`` of wall time; what the viewer achieved."""
    app.player.seek(app.recording.t_start_us)
    app.player.wait_idle(600)
    # Media seconds already computed when playing starts (the run-ahead works while the browser opens).
    ready = app.player.call(lambda e: getattr(e, "ready_steps", getattr(e, "frontier", 0)) * (getattr(e, "step_us", 0) or 0) / 1e6).result(60)
    meter.reset()
    t_media0 = app.last_frame.t_us
    frames0 = app.frames_published
    cpu0, kids0, load0 = *_cpu_s(), os.getloadavg()[0]
    t0 = time.perf_counter()
    app.player.play()
    app.player.call(lambda e: None).result(600)  # the play command handled (a loaded machine delayed it past 0.5 s)
    # Until ``seconds`` have passed or playback stopped at the end of the recording (then only until then).
    time.sleep(0.5)
    while time.perf_counter() - t0 < seconds and app.player.state.value == "playing":
        time.sleep(0.05)
    wall = time.perf_counter() - t0
    app.player.pause()
    app.player.wait_idle(600)
    cpu1, kids1 = _cpu_s()
    media = (app.last_frame.t_us - t_media0) / 1e6
    out = {"ready_media_s_at_start": ready, "wall_s": wall, "media_s": media, "real_time_factor": media / wall,
           "ui_frames_per_s": (app.frames_published - frames0) / wall,
           "server_cpu_s": cpu1 - cpu0, "browser_cpu_s": kids1 - kids0, "loadavg_1min": [load0, os.getloadavg()[0]]}
    if meter.wall_ms:
        out.update(draw_wall_median_ms=float(np.median(meter.wall_ms)), draw_wall_p95_ms=float(np.percentile(meter.wall_ms, 95)),
                   draw_cpu_median_ms=float(np.median(meter.cpu_ms)))
    return out


def _paused_browser_cpu(app, seconds: float) -> float:
    """CPU seconds per second the attached browser uses while the viewer is paused (and the run-ahead done)."""
    app.player.pause()
    app.player.wait_idle(600)
    _, kids0 = _cpu_s()
    time.sleep(seconds)
    return (_cpu_s()[1] - kids0) / seconds


def _wait_run_ahead(app, timeout_s: float = 1800.0) -> float:
    """Block until the run-ahead has reached the end of the recording and filled in the frames far seeks
    skipped; seconds waited."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout_s:
        done = app.player.call(lambda e: getattr(e, "frontier", 0) >= getattr(e, "n_steps", 0)
                               and not getattr(e, "backfill_left", 0)).result(600)
        if done:
            break
        time.sleep(0.25)
    return time.perf_counter() - t0


def headless_real_time_factor(rec_path: Path, map_path: Path, seconds: float) -> dict:
    """Baseline in the same run: the tracker alone (plain steps, and debug products on every step) over ``seconds`` of media."""
    from app.browser import load_map, load_recording
    from evpose.tracker.session import TrackingSession

    rec, cmap = load_recording(rec_path), load_map(map_path)
    out = {}
    for name, debug in (("plain", False), ("debug_every_step", True)):
        s = TrackingSession(rec, cmap)
        s.step(debug=debug)  # numba caches outside the timing
        t0_media, t0, c0 = s.t_us, time.perf_counter(), time.thread_time()
        while s.t_us - t0_media < seconds * 1e6 and s.step(debug=debug) is not None:
            del s.results[:]
        wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
        media = (s.t_us - t0_media) / 1e6
        out[f"headless_{name}_real_time_factor"] = media / wall
        out[f"headless_{name}_cpu_ms_per_step"] = cpu * 1e3 / max((s.t_us - t0_media) // s.dt_us, 1)
    return out


def bench_playback(ctx) -> dict:
    """Play the moderate demo at 1x with all panels on and headless Chromium attached: right after loading, and once the run-ahead is done."""
    from playwright.sync_api import sync_playwright

    seconds = PLAY_SECONDS or (4.0 if ctx.quick else 8.0)
    rec, cmap = demo_pair(Path(ctx.work_dir))
    _cache_dir(Path(ctx.work_dir), clear=True)
    t_load = time.perf_counter()
    app = _viewer(rec, cmap, Path(ctx.work_dir))
    out: dict = {"recording": str(rec)}
    try:
        with sync_playwright() as p:
            browser = _attach_browser(p, app)
            meter = DrawMeter(app.player)
            out["cold"] = _play(app, meter, seconds)
            _wait_run_ahead(app)
            out["run_ahead_done_after_load_s"] = time.perf_counter() - t_load
            cache = app.player.call(lambda e: (len(e.cache), e.cache.nbytes, e.cache.every) if hasattr(e, "cache") else None).result(60)
            if cache:
                out["frame_cache"] = {"frames": cache[0], "mb": cache[1] / 2**20, "every_steps": cache[2]}
            out["warm"] = _play(app, meter, seconds)
            out["paused_browser_cpu_s_per_s"] = _paused_browser_cpu(app, 3.0)
            browser.close()
    finally:
        app.stop()
    # A second opening of the same recording, map and configuration: read back from the disk cache.
    app = _viewer(rec, cmap, Path(ctx.work_dir))
    try:
        with sync_playwright() as p:
            browser = _attach_browser(p, app)
            # Steps read back (0 if the code under the key changed since the cold run, e.g. a colleague's edit).
            read = app.player.call(lambda e: getattr(e, "disk_steps", None)).result(60)
            out["from_disk"] = {"disk_steps_read": read, **_play(app, DrawMeter(app.player), seconds)}
            browser.close()
    finally:
        app.stop()
    out.update(headless_real_time_factor(rec, cmap, min(seconds, 2.0)))
    return out


def bench_seek(ctx) -> dict:
    """Seek latency (command -> frame drawn by the viewer, browser attached) at random times: right after loading
    (the run-ahead has barely started), once it is done, and exact (off-grid) seeks for comparison."""
    from playwright.sync_api import sync_playwright

    from evpose.bench.stats import latency_summary

    rec_path, map_path = demo_pair(Path(ctx.work_dir))
    n = N_SEEKS or (4 if ctx.quick else 10)
    rng = np.random.default_rng(ctx.seed)
    _cache_dir(Path(ctx.work_dir), clear=True)
    app = _viewer(rec_path, map_path, Path(ctx.work_dir))
    out: dict = {"recording": str(rec_path)}

    previews: list[float] = []

    def timed_seek(meter, t):
        """Command -> the seek's frame drawn, ms; a far seek's preview drawn before it goes to ``previews``."""
        meter.drawn.clear()
        meter.preview_at = None
        t0 = time.perf_counter()
        app.player.seek(int(t))
        meter.drawn.wait(600)
        app.player.wait_idle(600)
        if meter.preview_at is not None:
            previews.append((meter.preview_at - t0) * 1e3)
        return (time.perf_counter() - t0) * 1e3

    try:
        rec = app.recording
        span = rec.t_end_us - rec.t_start_us
        out["duration_s"] = span / 1e6
        with sync_playwright() as p:
            browser = _attach_browser(p, app)
            meter = DrawMeter(app.player)
            for phase in ("before_run_ahead", "after_run_ahead"):
                if phase == "after_run_ahead":
                    out["run_ahead_wait_s"] = _wait_run_ahead(app)
                load0 = os.getloadavg()[0]
                targets = rec.t_start_us + (rng.random(n) * span).astype(np.int64)
                previews.clear()
                far = timed_seek(meter, rec.t_start_us + int(0.95 * span))
                far_preview = previews[0] if previews else None
                lat = [timed_seek(meter, t) for t in targets]
                frontier = app.player.call(lambda e: getattr(e, "frontier", None)).result(60)
                out[phase] = {"far_seek_ms": far, "far_seek_preview_ms": far_preview, "previews": len(previews),
                              **({"preview_max_ms": max(previews)} if previews else {}),
                              **latency_summary(lat + [far], prefix="seek_"),
                              "frontier_after": frontier, "loadavg_1min": [load0, os.getloadavg()[0]]}
            # Exact seeks (not snapped to the frame grid) on the engine alone: what a step off the grid costs.
            targets = rec.t_start_us + (rng.random(max(n // 2, 2)) * span).astype(np.int64) + 1000
            exact = []
            for t in targets:
                t0 = time.perf_counter()
                app.player.call(lambda e, t=t: e.seek(int(t))).result(600)
                exact.append((time.perf_counter() - t0) * 1e3)
            out["exact_engine_seek"] = latency_summary(exact, prefix="seek_")
            browser.close()
    finally:
        app.stop()
    # A second opening (same recording, map, configuration): seeks right after loading, answered from the disk cache.
    app = _viewer(rec_path, map_path, Path(ctx.work_dir))
    try:
        with sync_playwright() as p:
            browser = _attach_browser(p, app)
            meter = DrawMeter(app.player)
            read = app.player.call(lambda e: getattr(e, "disk_steps", None)).result(60)
            load0 = os.getloadavg()[0]
            targets = rec.t_start_us + (rng.random(n) * span).astype(np.int64)
            far = timed_seek(meter, rec.t_start_us + int(0.95 * span))
            lat = [timed_seek(meter, t) for t in targets]
            frontier = app.player.call(lambda e: getattr(e, "frontier", None)).result(60)
            out["from_disk"] = {"disk_steps_read": read, "far_seek_ms": far, **latency_summary(lat + [far], prefix="seek_"),
                                "run_ahead_frontier_after": frontier, "loadavg_1min": [load0, os.getloadavg()[0]]}
            browser.close()
    finally:
        app.stop()
    return out


def bench_run_ahead(ctx) -> dict:
    """CPU per step of the run-ahead alone (no browser): debug products on every step (the old grid) vs on the
    20 ms grid (the default), and plain stepping; the same steps, alternated, in one run."""
    from app.browser import load_map, load_recording
    from app.frame_cache import FrameCacheConfig
    from app.tracker_engine import TrackerEngine

    rec_path, map_path = demo_pair(Path(ctx.work_dir))
    rec, cmap = load_recording(rec_path), load_map(map_path)
    n = 200 if ctx.quick else 600
    out: dict = {"recording": str(rec_path), "steps": n, "loadavg_1min": [os.getloadavg()[0]]}
    cpu: dict[str, list[float]] = {"every_step_5ms": [], "grid_20ms": [], "plain": []}
    for _ in range(2):  # alternate, so a change of machine load hits all alike
        for name in cpu:
            every = {"every_step_5ms": 5.0, "grid_20ms": 20.0, "plain": 1e9}[name]
            eng = TrackerEngine(rec, cmap, cache=FrameCacheConfig(every_ms=every))  # "plain": no grid step after step 0
            eng.prefetch(1)  # numba caches and the first snapshot outside the timing
            c0, w0 = time.thread_time(), time.perf_counter()
            eng.prefetch(n)
            cpu[name].append((time.thread_time() - c0) * 1e3 / n)
            out.setdefault(f"{name}_wall_ms_per_step", []).append((time.perf_counter() - w0) * 1e3 / n)
    for name, v in cpu.items():
        out[f"{name}_cpu_ms_per_step"] = v
        out[f"{name}_cpu_real_time_cores"] = min(v) / (eng.step_us / 1e3)
    out["loadavg_1min"].append(os.getloadavg()[0])
    return out


def _far_seek_player(rec, cmap, t_us: int, factory=None) -> dict:
    """The same seek through the player (run-ahead on, as ``evpose app`` runs it): when the status line first
    says how far it is, and when the frame is drawn. ``factory``: the engines (default: no disk cache)."""
    from app.player import Player
    from app.tracker_engine import TrackerEngine

    drawn, first_progress, previews, drawn_at = threading.Event(), [], [], []

    def on_frame(f, e):
        if f.preview:
            previews.append(time.perf_counter())
        else:
            drawn_at.append(time.perf_counter())
            drawn.set()

    t_open = time.perf_counter()
    p = Player(factory or (lambda cfg: TrackerEngine(rec, cmap, cfg)), on_frame,
               on_progress=lambda e: first_progress or first_progress.append(time.perf_counter()))
    try:
        p.seek(rec.t_start_us)
        p.wait_idle(600)
        open_s = time.perf_counter() - t_open  # engine made (a prepared one reads the disk cache) and step 0 drawn
        p.call(lambda e: e.prefetch(5)).result(600)
        drawn.clear()
        drawn_at.clear()
        load0 = os.getloadavg()[0]
        first_progress.clear()
        t0 = time.perf_counter()
        p.seek(t_us)
        # Commands sent while it computes wait at most one slice: time a few (they do nothing).
        time.sleep(1.0)
        waits = []
        for _ in range(5):
            c0 = time.perf_counter()
            p.call(lambda e: None).result(600)
            waits.append((time.perf_counter() - c0) * 1e3)
            time.sleep(0.2)
        drawn.wait(600)
        wall = drawn_at[0] - t0  # when it was drawn, however long the command probes above took
        p.wait_idle(600)
        return {"open_s": open_s, "first_status_update_s": (first_progress[0] - t0) if first_progress else None,
                "preview_drawn_s": (previews[0] - t0) if previews else None, "frame_drawn_s": wall,
                "command_wait_while_computing_ms": waits, "catch_up": p.last_catch_up,
                "loadavg_1min": [load0, os.getloadavg()[0]]}
    finally:
        p.stop()


def bench_far_seek(ctx) -> dict:
    """A seek to 95 % of the recording right after opening it (nothing computed there yet), on the engine alone:
    the old path (the run-ahead steps there keeping every grid frame) and the catch-up (plain steps, then the
    target step), alternated in one run; then through the player, which shows progress while it computes; then in a
    recording prepared, fully and half-way."""
    from app.bench_seek import exact_seek_prepared, far_seek_once, far_seek_partly_prepared
    from app.browser import load_map, load_recording

    rec_path, map_path = demo_pair(Path(ctx.work_dir))
    rec, cmap = load_recording(rec_path), load_map(map_path)
    t = rec.t_start_us + int(0.95 * (rec.t_end_us - rec.t_start_us))
    out: dict = {"recording": str(rec_path), "target_s": (t - rec.t_start_us) / 1e6}
    for _ in range(1 if ctx.quick else 2):
        for name, catch_up in (("grid_stepping", False), ("catch_up", True)):
            out.setdefault(name, []).append(far_seek_once(rec, cmap, t, catch_up))
            out[name][-1].pop("pose")
    out["player"] = _far_seek_player(rec, cmap, t)
    from app.bench_prepared import far_seek_prepared

    # The same seek through the player once the viewer's warm-up has prepared the recording (its time included).
    out["prepared"] = far_seek_prepared(rec_path, map_path, rec, cmap, t, Path(ctx.work_dir))
    # The disk holding only the first half: resume from its last disk snapshot vs from step 0 (app/bench_seek.py).
    out["partly_prepared"] = far_seek_partly_prepared(rec_path, map_path, rec, cmap, t, Path(ctx.work_dir))
    # Prepared to the end: an exact seek off the kept-frame grid, from the disk snapshot before it vs the run-ahead.
    out["exact_prepared"] = exact_seek_prepared(rec_path, map_path, rec, cmap, t + 7_000, Path(ctx.work_dir))
    return out


from app.bench_prepared import bench_warm_up_interference  # noqa: E402 (they import helpers from this module lazily)
from app.bench_start import bench_run_ahead_start  # noqa: E402

BENCHMARKS = {"playback_realtime": bench_playback, "seek_latency": bench_seek, "run_ahead_cpu": bench_run_ahead,
              "far_seek": bench_far_seek, "run_ahead_start": bench_run_ahead_start,
              "warm_up_interference": bench_warm_up_interference}


def main(argv: list[str] | None = None) -> None:
    import argparse

    from evpose.bench import BenchContext

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work-dir", type=Path, default=Path("/tmp/evpose_app_bench"))
    ap.add_argument("--full", action="store_true", help="longer runs (default: quick)")
    ap.add_argument("--only", choices=sorted(BENCHMARKS), default=None)
    ap.add_argument("--recording", type=Path, default=None, help="recording to use instead of the moderate demo")
    ap.add_argument("--map", type=Path, default=None, help="its contour map")
    ap.add_argument("--seconds", type=float, default=None, help="wall seconds of each playback phase")
    ap.add_argument("--seeks", type=int, default=None, help="random seek targets per phase")
    ap.add_argument("--background-warm-up", type=Path, nargs="*", default=[],
                    help="recordings the viewer's warm-up prepares over and over while the benchmarks run (maps from maps/)")
    args = ap.parse_args(argv)
    # Run as ``python -m app.bench`` this module is __main__: benchmarks elsewhere that import app.bench must see these settings.
    sys.modules.setdefault("app.bench", sys.modules[__name__])
    global DEMO_OVERRIDE, PLAY_SECONDS, N_SEEKS
    PLAY_SECONDS, N_SEEKS = args.seconds, args.seeks
    if args.recording is not None and args.map is not None:
        DEMO_OVERRIDE = (args.recording, args.map)
    ctx = BenchContext(quick=not args.full, work_dir=args.work_dir)
    from contextlib import nullcontext

    from app.bench_prepared import BackgroundWarmUp

    busy = lambda: CURRENT_VIEWER is not None and CURRENT_VIEWER._player_busy()  # noqa: E731
    with (BackgroundWarmUp(args.background_warm_up, Path("maps"), args.work_dir, busy) if args.background_warm_up
          else nullcontext()) as background:
        for name, fn in BENCHMARKS.items():
            if args.only and name != args.only:
                continue
            print(json.dumps({name: fn(ctx)}, indent=1), flush=True)
    if background is not None:
        print(json.dumps({"background_warm_up": background.report()}, indent=1), flush=True)


if __name__ == "__main__":
    main()
