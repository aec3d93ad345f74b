"""``evpose bench`` end to end: simulate -> track every (scenario, mode, rate) -> micro-benchmarks -> peers -> report.

All phases go through the same runner and the same per-job cache in
``OUT/jobs``, so an interrupted suite restarted with the same ``--out`` picks up
where it stopped. Simulated data lives in ``OUT/data`` (or ``--data``) and is
reused across runs and suites with the same settings.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from evpose.eval.cache import Job, ResultCache
from evpose.eval.runner import RunnerConfig, run_jobs
from evpose.eval.scenarios import scenario_paths
from evpose.eval.suite import SUITES, SuiteConfig, SuiteName, SuiteRun, scenario_specs, simulation_jobs, tracking_jobs


def runner_description(cfg: RunnerConfig) -> str:
    if cfg.scheduler:
        return f"Dask scheduler at {cfg.scheduler}"
    if cfg.workers <= 1:
        return "in-process, serial"
    return f"local process pool, {cfg.workers} workers"


def run_bench(
    suite: SuiteName,
    out_dir: str | Path,
    runner: RunnerConfig = RunnerConfig(),
    data_dir: str | Path | None = None,
    micro: bool = True,
    peers: bool = True,
    config: SuiteConfig | None = None,
) -> SuiteRun:
    """Run a suite (``config`` overrides the named suite's settings, e.g. for tests) and return everything measured."""
    cfg = config or SUITES[suite]
    out_dir = Path(out_dir)
    data = str(Path(data_dir) if data_dir else out_dir / "data")
    cache = ResultCache(out_dir / "jobs")
    result = SuiteRun(suite, cfg)
    t0 = time.perf_counter()

    def lap(phase: str, since: float) -> float:
        now = time.perf_counter()
        result.phases_s[phase] = now - since
        return now

    sim_jobs = simulation_jobs(cfg, data)
    sim_out = run_jobs(sim_jobs, cache, runner, desc="simulate")
    t = lap("simulate", t0)
    result.simulations = [{"job": j.name, **o} for j, o in zip(sim_jobs, sim_out)]
    ok_scenarios = {j.params["spec"]["scenario"] for j, o in zip(sim_jobs, sim_out) if o["ok"]}
    sim_error = {j.params["spec"]["scenario"]: o.get("error", "") for j, o in zip(sim_jobs, sim_out) if not o["ok"]}

    track = tracking_jobs(cfg, data)
    runnable = [j for j in track if j.params["spec"]["scenario"] in ok_scenarios]
    # One fresh process per tracking run: its peak memory is then its own.
    track_out = run_jobs(runnable, cache, replace(runner, fresh_process=True), desc="track")
    result.runs = {j.name: o for j, o in zip(runnable, track_out)}
    for j in track:
        if j.name not in result.runs:
            result.runs[j.name] = {"ok": False, "error": f"simulation failed: {sim_error.get(j.params['spec']['scenario'], '')}", "cached": False}
    t = lap("track", t)

    if micro:
        from evpose.bench import collect

        names = sorted(collect())
        mjobs = [Job(f"micro/{n}", "evpose.eval.suite:micro_benchmark_job", {"name": n, "quick": suite is SuiteName.QUICK, "work_dir": str(out_dir / "micro"), "seed": cfg.seed}) for n in names]
        result.micro = {j.params["name"]: o for j, o in zip(mjobs, run_jobs(mjobs, cache, runner, desc="micro-benchmarks"))}
        t = lap("micro-benchmarks", t)

    if peers:
        specs = scenario_specs(cfg)
        base = next((s for s in specs if s.scenario == "landing" and s.scenario in ok_scenarios), None)
        base = base or next((s for s in specs if s.scenario in ok_scenarios), None)
        if base is not None:
            rec_path, _ = scenario_paths(base, data)
            pjob = Job("peers/dv-processing", "evpose.bench.peers:compare_job", {"recording_path": str(rec_path)})
            result.peers = run_jobs([pjob], cache, runner, desc="peers")[0]
            t = lap("peers", t)

    result.wall_s = time.perf_counter() - t0
    return result
