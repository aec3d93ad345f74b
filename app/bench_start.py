"""Viewer benchmark ``run_ahead_start``: how soon after the server starts the run-ahead computes, before any browser connects.

Each run is a fresh process (imports count, as when ``evpose app`` starts) with an
empty disk cache (a first opening). Run with ``python -m app.bench --only run_ahead_start``.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

WAIT_S = 5.0
"""Seconds after the viewer's construction began at which the run-ahead's progress is read, seconds."""


def measure_once(rec: Path, cmap: Path, work_dir: Path) -> dict:
    """In this process: build the viewer on ``rec`` and ``cmap`` and time its run-ahead's first step."""
    import app.tracker_engine as te
    from app.bench import free_port
    from app.disk_cache import DiskCacheConfig
    from app.server import AppConfig, ViewerApp

    first: list[float] = []
    original = te.TrackerEngine.prefetch

    def prefetch(self, budget_steps: int = 5):
        if not first:
            first.append(time.perf_counter())
        return original(self, budget_steps)

    te.TrackerEngine.prefetch = prefetch
    shutil.rmtree(work_dir / "start_cache", ignore_errors=True)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    app = ViewerApp(AppConfig(data=sorted({rec.parent.resolve(), cmap.parent.resolve()}), port=free_port(),
                              export_dir=work_dir / "exports", disk_cache=DiskCacheConfig(directory=work_dir / "start_cache")))
    built = time.perf_counter() - t0
    time.sleep(max(0.0, WAIT_S - built))
    try:
        shown = (app.rec_dropdown.value, app.map_dropdown.value)
        return {"viewer_built_s": built, "first_run_ahead_step_s": (first[0] - t0) if first else None,
                "steps_after_wait": app.player.engine.frontier if app.player is not None else 0, "shown": shown,
                "loadavg_1min": [load0, os.getloadavg()[0]]}
    finally:
        app.stop()


def bench_run_ahead_start(ctx) -> dict:
    """Seconds from the viewer's construction to its run-ahead's first step, and steps computed WAIT_S after it began."""
    from app.bench import demo_pair

    rec, cmap = demo_pair(Path(ctx.work_dir))
    runs = []
    for _ in range(2 if ctx.quick else 6):
        out = subprocess.run([sys.executable, "-m", "app.bench_start", str(rec), str(cmap), str(ctx.work_dir)],
                             capture_output=True, text=True, check=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    firsts = [r["first_run_ahead_step_s"] for r in runs if r["first_run_ahead_step_s"] is not None]
    return {"recording": str(rec), "wait_s": WAIT_S, "runs": runs,
            "first_run_ahead_step_s_median": statistics.median(firsts) if firsts else None,
            "steps_after_wait_median": statistics.median(r["steps_after_wait"] for r in runs)}


if __name__ == "__main__":
    print(json.dumps(measure_once(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]))), flush=True)
