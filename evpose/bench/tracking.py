"""Tracking benchmarks: STPE accuracy (ATE/ARE, no alignment: we start from ground truth) and per-update latency
on the simulator's moderate landing scenario at 240x180 and 346x260, map from ``build_contour_map`` on the raw cloud.

Simulations and maps are cached under ``ctx.work_dir`` (they take minutes on the
shared 2-core machine). Latency is reported per module (wall time, as the
tracker measures it) and as the CPU time of each whole update, because the
cores are shared with other processes and wall time then includes queueing.
"""

from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path

import numpy as np

from evpose.bench import BenchContext
from evpose.bench.stats import latency_summary, peak_rss_mb

MODULES = ("noise_filter", "time_surface", "culling", "distance_field", "polarity_filter", "registration", "fusion", "total", "total_cpu")
"""Per-update timings summarised; ``total_cpu`` is the CPU time of ``Tracker.step`` alone (the update the latency
target is about), ``update_cpu_`` that of the whole session step (it adds the session's periodic snapshots)."""


def _mapping_key() -> str:
    """Hex digest of every source file of ``evpose.mapping`` (a changed map builder must not reuse old maps)."""
    import evpose.mapping

    h = hashlib.sha256()
    for src in sorted(Path(evpose.mapping.__file__).parent.glob("*.py")):
        h.update(src.name.encode())
        h.update(src.read_bytes())
    return h.hexdigest()[:16]


def landing_case(work_dir: Path, resolution: tuple[int, int], seconds: float, seed: int = 0, scenario: str = "landing"):
    """(Recording, ContourMap) of the moderate landing scenario (or another simulator ``scenario``), simulated and
    mapped once, then read from the cache.

    The simulation is cached by :func:`evpose.sim.cache.load_or_simulate`, keyed by
    the configuration *and* the simulator's source; the map next to it, keyed also
    by the map builder's source. (An earlier cache keyed only by resolution and
    duration silently paired the tracker with stale simulations and maps.)
    """
    from evpose.io.map_ply import read_contour_map, write_contour_map
    from evpose.sim import SimulationConfig
    from evpose.sim.cache import load_or_simulate, simulation_key

    w, h = resolution
    config = SimulationConfig(scenario=scenario, seconds=seconds, resolution=(w, h), seed=seed)
    cache = Path(work_dir) / "tracking" / "sim"
    map_path = cache / f"{scenario}_map-{simulation_key(config)}-{_mapping_key()}.ply"
    result = load_or_simulate(config, cache)
    if not map_path.is_file():
        from evpose.mapping import build_contour_map

        write_contour_map(map_path, build_contour_map(result.cloud_points, intensity=result.cloud_intensity))  # atomic
    return result.recording, read_contour_map(map_path)


def track_and_score(recording, contour_map, config=None) -> dict:
    """Run a TrackingSession from ground truth to the end; accuracy, losses and latency figures."""
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.tracker.config import TrackerConfig
    from evpose.tracker.session import TrackingSession
    from evpose.tracker.step_result import TrackStatus

    session = TrackingSession(recording, contour_map, config or TrackerConfig())
    cpu_ms = []
    while True:
        c0 = time.thread_time()
        r = session.step()
        if r is None:
            break
        cpu_ms.append((time.thread_time() - c0) * 1e3)
    results = session.results
    lost = [r for r in results if r.status is not TrackStatus.OK]
    out = {
        "updates": len(results),
        "lost_updates": len(lost),
        "lost_only_updates": sum(r.status is TrackStatus.LOST for r in results),
        "degraded_updates": sum(r.status is TrackStatus.DEGRADED for r in results),
        "first_lost_s": (lost[0].t_us - session.t0_us) * 1e-6 if lost else -1.0,
        "events": len(recording.events),
    }
    cfg = EvalConfig(align=Alignment.NONE)
    for name, traj in (("", session.trajectory()), ("all_", session.trajectory(include_lost=True))):
        if len(traj) >= 3:
            ev = evaluate(traj, recording.ground_truth, cfg)
            out[f"{name}ate_rmse_mm"] = ev.ate["rmse"] * 1e3
            out[f"{name}ate_max_mm"] = ev.ate["max"] * 1e3
            out[f"{name}are_rmse_deg"] = ev.are["rmse"]
    # Skip the first updates (numba and cache warm-up) in latency figures.
    warm = results[5:] if len(results) > 10 else results
    for m in MODULES:
        out.update(latency_summary([r.timings_ms[m] for r in warm if m in r.timings_ms], f"{m}_"))
    out.update(latency_summary(cpu_ms[5:] if len(cpu_ms) > 10 else cpu_ms, "update_cpu_"))
    out["points_used_median"] = float(np.median([r.counts.get("points_used", 0) for r in results]))
    out["iterations_median"] = float(np.median([r.counts.get("iterations", 0) for r in results]))
    out["load_average_1min"] = os.getloadavg()[0]
    out["peak_rss_mb"] = peak_rss_mb()
    return out


def _bench(resolution):
    def run(ctx: BenchContext) -> dict:
        seconds = 1.0 if ctx.quick else 2.0
        rec, cmap = landing_case(ctx.work_dir, resolution, seconds, ctx.seed)
        out = {"resolution": f"{resolution[0]}x{resolution[1]}", "seconds": seconds, "map_points": len(cmap)}
        out.update(track_and_score(rec, cmap))
        return out

    run.__doc__ = f"STPE on the moderate landing scenario at {resolution[0]}x{resolution[1]}, from ground truth."
    return run


def _bias(ctx: BenchContext) -> dict:
    """Registration started at ground truth (perfect and built map): bias, RMS error and covariance consistency."""
    from evpose.bench.registration_bias import registration_bias

    return registration_bias(ctx.work_dir, (346, 260), 1.0 if ctx.quick else 2.0, ctx.seed)


def _superset_culling(ctx: BenchContext) -> dict:
    """Whole-map superset cull of the landing map (346x260) along the ground truth: per-point pass vs block-wise pass.

    Both run in the same process on the same poses (CPU time, thread_time), so the
    ratio is meaningful on the shared machine; they must return the same indices.
    """
    import dataclasses

    from evpose.tracker.config import TrackerConfig
    from evpose.tracker.visible_map import VisibleMap, visible_points

    rec, cmap = landing_case(ctx.work_dir, (346, 260), 1.0 if ctx.quick else 2.0, ctx.seed)
    cal = rec.calibration
    points = np.ascontiguousarray(cmap.points, dtype=np.float64)
    vm = VisibleMap(points, cal.K, cal.width, cal.height)
    base = TrackerConfig().visible_map
    wide = dataclasses.replace(base, fov_margin_px=base.fov_margin_px + vm.extra_px, occlusion=False)
    gt = rec.ground_truth
    poses = gt.interpolate(np.linspace(gt.t[0], gt.t[-1], 40).astype(np.int64)).matrices()
    per_point, blocks = [], []
    same = True
    for T in poses:
        for _ in range(2):  # first call of each compiles / warms caches; keep the second
            c0 = time.thread_time()
            a = visible_points(points, T, cal.K, cal.width, cal.height, wide)
            c1 = time.thread_time()
            b = vm._superset(T, wide)
            c2 = time.thread_time()
        per_point.append((c1 - c0) * 1e3)
        blocks.append((c2 - c1) * 1e3)
        same &= bool(np.array_equal(a, b))
    out = {"map_points": len(points), "identical": same, "load_average_1min": os.getloadavg()[0]}
    out.update(latency_summary(per_point, "per_point_cpu_"))
    out.update(latency_summary(blocks, "blocks_cpu_"))
    return out


def _registration_cost(ctx: BenchContext) -> dict:
    """``register_to_map`` latency against the point count and its per-call / per-point split (registration_cost)."""
    from evpose.bench.registration_cost import bench_registration_cost

    return bench_registration_cost(ctx)


BENCHMARKS = {"landing_240x180": _bench((240, 180)), "landing_346x260": _bench((346, 260)), "registration_bias_346x260": _bias,
              "superset_culling_346x260": _superset_culling,
              "registration_cost": _registration_cost}
