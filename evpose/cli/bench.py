"""``evpose bench``: the benchmark suite (simulated scenarios x modes x rates, micro-benchmarks, peers) -> report."""

from __future__ import annotations

from pathlib import Path
from typing import Literal


def main(
    suite: Literal["quick", "full"] = "quick",
    out: Path = Path("bench_out"),
    data: Path | None = None,
    workers: int = 2,
    scheduler: str | None = None,
    micro: bool = True,
    peers: bool = True,
    progress: bool = True,
) -> int:
    """Run the benchmark suite and write OUT/report.md and OUT/report.json.

    Studies mirror the EV-Pose paper: latency of the systems (Table I), velocity
    (Fig. 15), frequency 100/200/300 Hz (Fig. 16), HDR (Fig. 17), scene dynamics
    (Fig. 18), module ablation (Fig. 19) and fusion frameworks (Fig. 20). Simulated
    recordings are generated on first use and cached; a rerun with the same --out
    resumes from the runs that already finished.

    Args:
        suite: quick (< 5 min here) or full (what a release quotes).
        out: Output folder: report, per-job results (OUT/jobs) and, by default, simulated data (OUT/data).
        data: Folder for the simulated recordings and maps (shared between output folders).
        workers: Local worker processes (0/1: run in this process).
        scheduler: Dask scheduler address (e.g. tcp://10.0.0.5:8786); jobs run there instead of locally.
        micro: Also run the registered micro-benchmarks.
        peers: Also compare against dv-processing where it is installed.
        progress: Show progress bars.
    """
    from evpose.eval.bench_run import run_bench, runner_description
    from evpose.eval.report import write_report
    from evpose.eval.runner import RunnerConfig
    from evpose.eval.suite import SuiteName

    from evpose.cli.runner_args import check_runner_args

    check_runner_args(workers, scheduler, (out, data))
    runner = RunnerConfig(workers=workers, scheduler=scheduler, progress=progress)
    result = run_bench(SuiteName(suite), out, runner, data_dir=data, micro=micro, peers=peers)
    md, js = write_report(result, out, runner_description(runner))
    failed = [name for name, o in result.runs.items() if not o.get("ok")]
    print(f"{len(result.runs)} runs ({len(failed)} failed) in {result.wall_s:.1f} s -> {md}, {js}")
    for name in failed[:10]:
        print(f"  {name}: {result.runs[name].get('error', '')}")
    return 0
