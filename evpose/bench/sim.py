"""Simulator benchmarks: simulation speed at 346x260 and 1280x720, per-scenario event rates, kernel speeds.

Timings on the shared 2-core machine are noisy; every figure is measured in
the same process so ratios (e.g. incremental vs full render) are comparable.
"""

from __future__ import annotations

import time

import numpy as np

from evpose.bench import BenchContext
from evpose.bench.stats import latency_summary, peak_rss_mb, repeat_timing


def _speed(ctx: BenchContext, resolution, seconds_quick, seconds_full, scenario="landing") -> dict:
    from evpose.sim import SimulationConfig, simulate

    seconds = seconds_quick if ctx.quick else seconds_full
    simulate(SimulationConfig(scenario=scenario, seconds=0.01, resolution=(32, 24), seed=ctx.seed))  # imports, numba caches
    t0, c0 = time.perf_counter(), time.process_time()
    r = simulate(SimulationConfig(scenario=scenario, seconds=seconds, resolution=resolution, seed=ctx.seed))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    n = len(r.recording.events)
    s = r.stats
    return {
        "scenario": scenario,
        "resolution": f"{resolution[0]}x{resolution[1]}",
        "simulated_s": seconds,
        "wall_s": wall,
        "sim_s_per_wall_s": seconds / wall,
        "cpu_s": cpu,
        "sim_s_per_cpu_s": seconds / cpu,
        "events": n,
        "events_per_wall_s": n / wall,
        "event_rate_hz": n / seconds,
        "renders": s["renders"],
        "render_ms_mean": 1e3 * s["render_s"] / max(s["renders"], 1),
        "rays_per_render": s["rays"] / max(s["renders"], 1),
        "esim_share": s["esim_s"] / wall,
        "peak_rss_mb": peak_rss_mb(),
    }


def speed_346x260(ctx: BenchContext) -> dict:
    """Simulated seconds per wall second and events per wall second, landing at 346x260."""
    return _speed(ctx, (346, 260), 0.5, 2.0)


def speed_1280x720(ctx: BenchContext) -> dict:
    """The same at 1280x720."""
    return _speed(ctx, (1280, 720), 0.1, 0.5)


def scenario_event_rates(ctx: BenchContext) -> dict:
    """Event rate (events per simulated second) of every scenario."""
    from evpose.sim import SimulationConfig, simulate
    from evpose.sim.scenarios import SCENARIOS

    res, seconds = ((240, 180), 0.2) if ctx.quick else ((346, 260), 1.0)
    out = {"resolution": f"{res[0]}x{res[1]}", "simulated_s": seconds}
    for name in SCENARIOS:
        t0 = time.perf_counter()
        r = simulate(SimulationConfig(scenario=name, seconds=seconds, resolution=res, seed=ctx.seed))
        out[f"{name}_event_rate_hz"] = len(r.recording.events) / seconds
        out[f"{name}_wall_s"] = time.perf_counter() - t0
    return out


def render_frame(ctx: BenchContext) -> dict:
    """Milliseconds per rendered frame, full vs incremental, 346x260 landing flight (0.5 px steps)."""
    from evpose.sim import SimulationConfig
    from evpose.sim.render import Renderer
    from evpose.sim.scenarios import SCENARIOS
    from evpose.sim.scene_library import build_scene
    from evpose.sim.simulator import make_calibration
    from evpose.sim.trajectories import RigTrajectory

    cal = make_calibration(SimulationConfig(resolution=(346, 260)), np.eye(4))
    sc = SCENARIOS["landing"]
    r = Renderer(build_scene(sc.scene, sc.options), cal)
    traj = RigTrajectory(sc.trajectory, 4.0)
    ts = np.arange(3.0, 3.0 + (0.05 if ctx.quick else 0.2), 0.001)
    poses = traj.camera_poses(ts)
    r.render(poses[0], ts[0])
    full = []
    for k in range(len(ts)):
        t0 = time.perf_counter()
        r.render(poses[k], ts[k])
        full.append(1e3 * (time.perf_counter() - t0))
    inc = []
    prev = r.render(poses[0], ts[0])
    for k in range(1, len(ts)):
        t0 = time.perf_counter()
        prev = r.render(poses[k], ts[k], previous=prev)
        inc.append(1e3 * (time.perf_counter() - t0))
    return {**latency_summary(full, "full_"), **latency_summary(inc, "incremental_"), "supersampled_share": float(prev.mark.mean())}


def esim_kernel(ctx: BenchContext) -> dict:
    """ESIM comparator throughput on a moving synthetic edge pattern, events per second."""
    from evpose.sim.esim import EsimConfig, EventGenerator

    w, h = 346, 260
    xs = np.arange(w)[None, :]
    frames = [np.log(0.3 + 0.6 * (np.sin((xs + 0.5 * k) / 3.0) > 0) + 0.0 * np.arange(h)[:, None]) for k in range(50)]
    state = {}

    def run():
        gen = EventGenerator(EsimConfig(c_sigma=0.03), w, h, np.random.default_rng(0))
        gen.reset(frames[0], 0)
        n = 0
        for k in range(1, len(frames)):
            n += len(gen.step(frames[k], 1000 * k))
        state["n"] = n

    times = repeat_timing(run, repeats=3 if ctx.quick else 7)
    med = float(np.median(times))
    return {"events": state["n"], "median_ms": med, "mev_per_s": state["n"] / med / 1e3, "frames_per_s": (len(frames) - 1) / med * 1e3}


BENCHMARKS = {
    "speed_346x260": speed_346x260,
    "speed_1280x720": speed_1280x720,
    "scenario_event_rates": scenario_event_rates,
    "render_frame": render_frame,
    "esim_kernel": esim_kernel,
}
