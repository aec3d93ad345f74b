"""``evpose sweep``: a parameter grid x recordings -> a table of metrics and the best configuration as YAML."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import tyro


def check_recording_item(item: str, target: str = "tracking") -> None:
    """Refuse a ``--recordings`` item that no job could read, before any job: a typo, an unknown scenario or a
    damaged file would otherwise become one failed job per configuration and exit 1 after the whole grid.

    Only the cheap checks: the scenario name, what opening the recording for streaming reads (format, schema,
    calibration, IMU, ground truth), the whole map. Bad events deep in a recording still fail its jobs, each naming file and record.
    """
    from evpose.errors import ConfigError, InputError

    if item.startswith("sim:"):
        from evpose.sim.scenarios import SCENARIOS

        if item[4:] not in SCENARIOS:
            raise ConfigError(f"--recordings {item}: unknown simulated scenario {item[4:]!r} (known: {', '.join(SCENARIOS)})")
        return
    parts = item.split("::")
    if target == "tracking" and len(parts) < 2:
        # Ran the whole grid, each job failing with "needs a contour map", and exited 1.
        raise ConfigError(f"--recordings {item}: tracking needs the recording's contour map: pass it as {item}::MAP.ply")
    for part in parts:
        if not Path(part).exists():
            raise InputError(part, "no such file or folder", f"--recordings {item}")
    from evpose.io.open import open_stream

    open_stream(parts[0])  # format, schema, calibration, IMU and ground truth; the events are not read
    if len(parts) > 1:
        from evpose.io.map_ply import read_contour_map

        read_contour_map(parts[1])


def main(
    grid: tyro.conf.Positional[list[str]],
    recordings: list[str],
    target: Literal["tracking", "noise-filter"] = "tracking",
    out: Path = Path("sweep_out"),
    score: str | None = None,
    maximize: bool = False,
    minimize: bool = False,
    workers: int = 2,
    scheduler: str | None = None,
    progress: bool = True,
) -> int:
    """Evaluate every combination of GRID values on every recording; write sweep.md, sweep.json, best_config.yaml.

    A rerun with the same --out resumes: finished (configuration, recording) jobs
    are read back from OUT/jobs instead of being run again.

    Args:
        grid: FIELD=VALUES items, dotted fields of the target's config, YAML values,
            e.g. noise_filter.window_us=[1000,3000] registration.max_iterations=[5,10].
        recordings: Recordings: PATH (noise-filter target), PATH::MAP.ply (recording with its contour map),
            or sim:SCENARIO (simulated recording and map, generated once and cached under $EVPOSE_CACHE or ~/.cache/evpose).
        target: What runs per job: the whole tracker (TrackerConfig) or the noise filter alone (NoiseFilterConfig).
        out: Output folder (results, per-job cache).
        score: Metric ranking configurations (default: ate_mean_m for tracking, kept_share for noise-filter).
        maximize: Higher score is better.
        minimize: Lower score is better.
        workers: Local worker processes (0/1: run in this process).
        scheduler: Dask scheduler address (e.g. tcp://10.0.0.5:8786); jobs run there instead of locally.
        progress: Show a progress bar.
    """
    from evpose.errors import ConfigError
    from evpose.eval.runner import RunnerConfig
    from evpose.eval.sweep import markdown_table, run_sweep

    if maximize and minimize:
        raise ConfigError("--maximize and --minimize exclude each other")
    from evpose.cli.runner_args import check_runner_args

    check_runner_args(workers, scheduler, (out,))
    for item in recordings:
        check_recording_item(item, target)
    direction = True if minimize else (False if maximize else None)
    result = run_sweep(target, list(grid), list(recordings), out, RunnerConfig(workers=workers, scheduler=scheduler, progress=progress), score=score, minimize=direction)
    print(markdown_table(result.table), end="")
    failed = sum(len(r["failed"]) for r in result.table["rows"])
    if failed:
        first = next(m["error"] for r in result.table["rows"] for m in r["recordings"].values() if "error" in m)
        print(f"{failed} job(s) failed; first error: {first}")
    if result.best_config is None:
        print("no configuration succeeded on every recording; no best_config.yaml written")
        return 1
    print(f"best configuration: #{result.table['best']} -> {Path(out) / 'best_config.yaml'}")
    return 0
