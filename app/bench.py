"""Viewer benchmarks: playback speed with every panel on in a real browser, and seek latency.

Same registry shape as ``evpose/bench/<area>.py`` (``BENCHMARKS = {name: fn(ctx) -> dict}``);
it lives in ``app/`` because ``evpose/`` must not import the viewer. Run it directly:
``python -m app.bench [--recording R.h5 --map M_map.ply] [--seconds S]``.
Timings on a shared 2-core machine are noisy; each benchmark reports a headless
baseline measured in the same run.
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


DEMO_OVERRIDE: tuple[Path, Path] | None = None
"""(recording, map) given on the command line, used instead of looking for the demo."""


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


def _viewer(rec: Path, cmap: Path, work_dir: Path):
    from app.player import PlayerConfig
    from app.server import AppConfig, ViewerApp

    app = ViewerApp(AppConfig(data=sorted({rec.parent.resolve(), cmap.parent.resolve()}), port=_free_port(),
                              export_dir=work_dir / "exports", player=PlayerConfig(prefetch=False)))
    rec_entry = next(e for e in app.entries if e.path == rec.resolve())
    map_entry = next(e for e in app.entries if e.path == cmap.resolve())
    if not app.select(rec_entry.display, map_entry.display):
        raise RuntimeError(app.rec_info.content)
    app.player.wait_idle(120)
    return app


def headless_real_time_factor(rec_path: Path, map_path: Path, seconds: float) -> dict:
    """Baseline: the tracker alone (no viewer, debug images on as the viewer asks) over the same span."""
    from app.browser import load_map, load_recording
    from app.engine import TrackerEngine

    eng = TrackerEngine(load_recording(rec_path), load_map(map_path))
    eng.step()  # compile / load numba caches outside the timing
    t0_media, t0 = eng.current_t_us, time.perf_counter()
    while eng.current_t_us - t0_media < seconds * 1e6 and eng.step() is not None:
        pass
    wall = time.perf_counter() - t0
    return {"headless_real_time_factor": (eng.current_t_us - t0_media) / 1e6 / wall, "headless_steps": len(eng.history)}


def bench_playback(ctx) -> dict:
    """Play the moderate demo at 1x for a few seconds with all panels on and a real browser attached."""
    from playwright.sync_api import sync_playwright

    seconds = 4.0 if ctx.quick else 10.0
    rec, cmap = demo_pair(Path(ctx.work_dir))
    app = _viewer(rec, cmap, Path(ctx.work_dir))
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.goto(f"http://127.0.0.1:{app.cfg.port}")
            page.get_by_text("SP-TS positive").first.wait_for(timeout=60_000)
            app.player.seek(app.recording.t_start_us)
            app.player.wait_idle(120)
            frames0, t_media0 = app.frames_published, app.last_frame.t_us
            t0 = time.perf_counter()
            app.player.play()
            time.sleep(seconds)
            app.player.pause()
            app.player.wait_idle(60)
            wall = time.perf_counter() - t0
            media = (app.last_frame.t_us - t_media0) / 1e6
            frames = app.frames_published - frames0
            steps = [s.timings_ms.get("total", np.nan) for s in app.player.engine.history]
            browser.close()
    finally:
        app.stop()
    out = {"recording": str(rec), "wall_s": wall, "media_s": media, "real_time_factor": media / wall,
           "ui_frames_per_s": frames / wall, "step_total_median_ms": float(np.nanmedian(steps)) if steps else float("nan")}
    out.update(headless_real_time_factor(rec, cmap, media if media > 0 else 1.0))
    return out


def bench_seek(ctx) -> dict:
    """Seek latency (command -> frame drawn) on a 10 s recording after the idle-time prefetch; without it a far seek replays from the start."""
    from app.browser import load_map, load_recording
    from app.engine import TrackerEngine
    from app.player import Player, PlayerConfig

    rec_path, map_path = demo_pair(Path(ctx.work_dir))
    rec, cmap = load_recording(rec_path), load_map(map_path)
    drawn = threading.Event()
    player = Player(lambda cfg: TrackerEngine(rec, cmap, cfg), lambda f, e: drawn.set(), player_config=PlayerConfig(prefetch=False))
    rng = np.random.default_rng(ctx.seed)
    span = rec.t_end_us - rec.t_start_us
    targets = rec.t_start_us + (rng.random(4 if ctx.quick else 10) * span).astype(np.int64)

    def timed_seek(t):
        drawn.clear()
        t0 = time.perf_counter()
        player.seek(int(t))
        drawn.wait(600)
        return (time.perf_counter() - t0) * 1e3

    try:
        player.step_forward()
        player.wait_idle(120)
        # Idle-time prefetch of the whole recording (what the paused viewer does on its own), timed.
        t0 = time.perf_counter()
        while player.call(lambda e: e.prefetch(50)).result(600):
            pass
        prefetch_s = time.perf_counter() - t0
        far = timed_seek(rec.t_start_us + int(0.95 * span))
        warm = [timed_seek(t) for t in targets]
    finally:
        player.stop()
    from evpose.bench.stats import latency_summary

    out = {"recording": str(rec_path), "duration_s": span / 1e6, "far_seek_after_prefetch_ms": far, "prefetch_whole_recording_s": prefetch_s}
    out.update(latency_summary(warm, prefix="seek_"))
    return out


BENCHMARKS = {"playback_realtime": bench_playback, "seek_latency": bench_seek}


def main(argv: list[str] | None = None) -> None:
    import argparse

    from evpose.bench import BenchContext

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work-dir", type=Path, default=Path("/tmp/evpose_app_bench"))
    ap.add_argument("--full", action="store_true", help="longer runs (default: quick)")
    ap.add_argument("--only", choices=sorted(BENCHMARKS), default=None)
    ap.add_argument("--recording", type=Path, default=None, help="recording to use instead of the moderate demo")
    ap.add_argument("--map", type=Path, default=None, help="its contour map")
    args = ap.parse_args(argv)
    global DEMO_OVERRIDE
    if args.recording is not None and args.map is not None:
        DEMO_OVERRIDE = (args.recording, args.map)
    ctx = BenchContext(quick=not args.full, work_dir=args.work_dir)
    for name, fn in BENCHMARKS.items():
        if args.only and name != args.only:
            continue
        print(json.dumps({name: fn(ctx)}, indent=1), flush=True)


if __name__ == "__main__":
    main()
