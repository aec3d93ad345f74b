"""SLAM benchmarks: event-image splatting, MCI generation and the main tracking thread per MCI at 346x260, and accuracy.

The synthetic scene (random 3D points, constant-rate events at their
projections) is generated here so the benchmark needs no simulator run; the
``scenario_*`` benchmarks (event-only and E-I-C2 on ``landing`` and ``indoor``)
use :mod:`evpose.sim` when it is present (slow: it renders the scene), caching
the recording in ``ctx.work_dir``. Each reports the 1-minute load average, since
wall times on a shared machine depend on the other processes.
"""

from __future__ import annotations

import pickle
import time
from pathlib import Path

import numpy as np

from evpose.bench import BenchContext
from evpose.bench.stats import latency_summary, peak_rss_mb, repeat_timing


def _synthetic(duration_s: float, seed: int):
    """346x260 camera flying sideways past 400 points at 1.5 m/s (same generator idea as the tests)."""
    from scipy.spatial.transform import Rotation

    from evpose.core.camera import CameraCalibration
    from evpose.core.events import EventArray
    from evpose.core.recording import Recording
    from evpose.core.trajectory import Trajectory, invert_pose

    rng = np.random.default_rng(seed)
    cal = CameraCalibration(346, 260, 280.0, 280.0, 172.5, 129.5)
    n = 400
    pts = np.c_[rng.uniform(-3.5, 3.5, n), rng.uniform(-2.6, 2.6, n), rng.uniform(3.0, 6.0, n)]
    t = np.arange(0.0, duration_s + 1e-9, 1e-3)
    pos = np.c_[1.5 * t - 0.75 * duration_s, 0.05 * np.sin(2 * t), 0.1 * np.sin(1.3 * t)]
    rot = Rotation.from_rotvec(np.c_[0.02 * np.sin(1.7 * t), 0.05 * np.sin(1.1 * t), 0.01 * t])
    gt = Trajectory.from_arrays((t * 1e6).astype(np.int64), pos, rot.as_quat())
    T = gt.matrices()
    pol = np.where(rng.random(n) < 0.5, 1, -1)
    ts, xs, ys, ps = [], [], [], []
    for k in range(len(t) - 1):
        Tc = invert_pose(T[k])
        Xc = pts @ Tc[:3, :3].T + Tc[:3, 3]
        uv = cal.project(Xc)
        vis = np.isfinite(uv).all(axis=1) & (uv[:, 0] >= 0) & (uv[:, 0] < 345) & (uv[:, 1] >= 0) & (uv[:, 1] < 259)
        idx = np.repeat(np.arange(n), rng.poisson(1.5, n) * vis)
        e = np.rint(uv[idx] + rng.normal(0, 0.35, (idx.size, 2)))
        ok = (e[:, 0] >= 0) & (e[:, 0] < 346) & (e[:, 1] >= 0) & (e[:, 1] < 260)
        ts.append(k * 1000 + rng.integers(0, 1000, ok.sum()))
        xs.append(e[ok, 0]); ys.append(e[ok, 1]); ps.append(pol[idx][ok])
    tt = np.concatenate(ts)
    o = np.argsort(tt, kind="stable")
    ev = EventArray.from_arrays(tt[o], np.concatenate(xs)[o], np.concatenate(ys)[o], np.concatenate(ps)[o])
    return Recording(events=ev, ground_truth=gt, calibration=cal, metadata={"scenario": "bench-synthetic-points"})


def strong_corner_count(mci: np.ndarray, quality: float = 0.05, fast_threshold: int = 8) -> int:
    """FAST corners of an MCI whose Shi-Tomasi response is at least ``quality`` of the image's best: corners KLT can pin down
    in both directions (points on straight edges slide along them). A scene-richness figure, not a pipeline stage."""
    import cv2

    from evpose.slam.event_image import to_uint8

    img8 = to_uint8(mci)
    kps = cv2.FastFeatureDetector_create(threshold=fast_threshold, nonmaxSuppression=True).detect(img8, None)
    if not kps:
        return 0
    pts = np.array([k.pt for k in kps]).round().astype(int)
    eig = cv2.cornerMinEigenVal(img8, blockSize=5, ksize=3)
    return int(np.sum(eig[pts[:, 1], pts[:, 0]] >= quality * float(eig.max())))


def bench_event_image(ctx: BenchContext) -> dict:
    """Throughput of the Gaussian event-image splat (bilinear votes + blur) at 346x260."""
    from evpose.slam.event_image import event_image

    rng = np.random.default_rng(ctx.seed)
    n = 50_000
    x, y = rng.uniform(0, 346, n), rng.uniform(0, 260, n)
    H = np.repeat(np.eye(3)[None], 24, axis=0)
    idx = rng.integers(0, 24, n)
    samples = repeat_timing(lambda: event_image(x, y, None, 346, 260, 1.0, idx, H), repeats=5 if ctx.quick else 20)
    out = latency_summary(samples)
    out["mev_per_s"] = n / (out["median_ms"] * 1e3)
    out["events"] = n
    return out


def _slam_latencies(rec, ctx: BenchContext, config=None) -> dict:
    import os

    import cv2

    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.slam import SlamConfig, SlamMode, run_slam

    config = config or SlamConfig()
    # Single-threaded OpenCV: the per-thread CPU timings then cover all the work, and the 2-core
    # machine is not oversubscribed by OpenCV's pool.
    cv2.setNumThreads(1)
    run_slam(rec.__class__(events=rec.events[: min(len(rec.events), 200_000)], calibration=rec.calibration), SlamConfig())  # numba warm-up
    load_before = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    run = run_slam(rec, config)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    res = [r for r in run.results]
    out = {}
    out.update(latency_summary([r.timings_ms["tracking"] for r in res], "tracking_"))
    out.update(latency_summary([r.timings_ms["mci"] for r in res], "mci_"))
    out.update(latency_summary([r.timings_ms["total"] for r in res], "per_mci_total_"))
    out.update(latency_summary([r.timings_ms["tracking_cpu"] for r in res], "tracking_cpu_"))
    out.update(latency_summary([r.timings_ms["mci_cpu"] for r in res], "mci_cpu_"))
    out["wall_s"] = wall
    # CPU time of this process is immune to other processes queueing on the shared cores.
    out["cpu_s"] = cpu
    out["cpu_ms_per_mci"] = 1e3 * cpu / max(len(res), 1)
    out["realtime_factor"] = run.duration_s / wall if wall > 0 else 0.0
    out["mcis"] = len(res)
    out["ok_share"] = float(np.mean([r.status.value == "ok" for r in res])) if res else 0.0
    # Time, not MCIs: the share of the recording tracked from the events (tracked_fraction counts coasted poses too).
    out["visual_fraction"] = run.visual_fraction
    # Wall times on a shared machine depend on the other processes: the load average says how busy it was.
    out["load_average_1min"] = float(max(load_before, os.getloadavg()[0]))
    out["mode"] = config.mode.value
    if config.mode is SlamMode.EVENT_INERTIAL:
        out["inertial_configuration"] = config.inertial.configuration.value
        out["inertial_mcis"] = int(sum(r.status.value == "inertial" for r in res))
    if rec.ground_truth is not None:
        # Event-only maps have an arbitrary scale; event-inertial maps are metric and are not rescaled.
        m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=config.mode is SlamMode.EVENT, duration_s=run.duration_s)
        out.update({"maps": len(m.maps), "tracked_fraction": m.tracked_fraction, "ate_percent": m.ate_percent,
                    "rpe_trans_per_m": m.rpe_trans_per_m, "rpe_rot_deg_per_m": m.rpe_rot_deg_per_m, "stability_m_s": m.stability})
        drift = m.to_dict()["scale_drift_percent_max"]
        if drift is not None:
            out["scale_drift_percent_max"] = drift  # spread of the 0.5 s segment scales of the worst map
    # How much a point-feature front end has to hold on to: strong corners per MCI (outside the timings above).
    corners = [strong_corner_count(r.mci) for r in res if r.mci is not None]
    if corners:
        out["strong_corners_median"] = float(np.median(corners))
        out["mcis_below_min_inliers_share"] = float(np.mean(np.array(corners) < config.tracking.min_inliers))
    out["peak_rss_mb"] = peak_rss_mb()
    return out


def bench_pipeline_synthetic(ctx: BenchContext) -> dict:
    """Event-only SLAM on the synthetic point scene at 346x260: per-MCI latencies (tracking thread and MCI), accuracy."""
    rec = _synthetic(1.5 if ctx.quick else 4.0, ctx.seed)
    return _slam_latencies(rec, ctx)


def bench_projection_search_ab(ctx: BenchContext) -> dict:
    """Cost and effect of re-finding map points by projection: the synthetic scene with the search on and off, same run."""
    from evpose.slam import SlamConfig

    rec = _synthetic(1.5 if ctx.quick else 4.0, ctx.seed)
    off = SlamConfig()
    off.search.enabled = False
    on = SlamConfig()
    on.search.enabled = True
    out = {}
    for name, cfg in (("off", off), ("on", on)):
        r = _slam_latencies(rec, ctx, cfg)
        for k in ("tracking_median_ms", "tracking_cpu_median_ms", "cpu_ms_per_mci", "ok_share", "tracked_fraction", "ate_percent",
                  "rpe_trans_per_m", "load_average_1min"):
            if k in r:
                out[f"{name}_{k}"] = r[k]
    return out


def _scenario_recording(ctx: BenchContext, scenario: str, seed: int | None = None):
    """The simulator's ``scenario``, 3 s at 346x260 (``seed``, default ``ctx.seed``), cached in ``ctx.work_dir``; None when the simulator is absent."""
    try:
        from evpose.sim import SimulationConfig, simulate
    except ImportError:
        return None
    from evpose.io.atomic import atomic_path
    from evpose.sim.cache import source_digest

    seed = ctx.seed if seed is None else int(seed)
    # Keyed by the simulator's source too: a changed simulator never reuses recordings made by older code.
    cache = ctx.work_dir / f"slam_{scenario}_3s_seed{seed}_{source_digest()[:12]}.pkl"
    if cache.exists():
        return pickle.loads(cache.read_bytes())
    rec = simulate(SimulationConfig(scenario=scenario, seconds=3.0, resolution=(346, 260), seed=seed)).recording
    ctx.work_dir.mkdir(parents=True, exist_ok=True)
    with atomic_path(cache) as tmp:
        Path(tmp).write_bytes(pickle.dumps(rec))
    return rec


def _scenario_bench(scenario: str, inertial: str | None):
    def bench(ctx: BenchContext) -> dict:
        if ctx.quick:
            return {"skipped": "full suite only (simulating takes minutes)"}
        from evpose.slam import SlamConfig, SlamMode
        from evpose.slam.inertial import InertialConfiguration

        rec = _scenario_recording(ctx, scenario)
        if rec is None:
            return {"skipped": "evpose.sim not available"}
        cfg = SlamConfig()
        if inertial is not None:
            cfg.mode = SlamMode.EVENT_INERTIAL
            cfg.inertial.configuration = InertialConfiguration(inertial)
        return _slam_latencies(rec, ctx, cfg)

    bench.__doc__ = (f"{'Event-only' if inertial is None else 'Event-inertial E-I-' + inertial.upper()} SLAM on the simulator's "
                     f"``{scenario}`` scenario, 3 s at 346x260 (full suite only; the recording is cached).")
    return bench


bench_scenario = _scenario_bench("landing", None)

LANDING_SEEDS = 24
"""Simulator seeds of the event-only landing spread benchmark (8 gave the opposite verdict to 24 on the BA scale anchor)."""


def bench_landing_seed_spread(ctx: BenchContext) -> dict:
    """Event-only SLAM on the ``landing`` scenario over ``LANDING_SEEDS`` simulator seeds (3 s at 346x260 each, full suite
    only, recordings cached): the spread of the scale-aligned ATE (% of distance), tracked share and maps. One recording
    says little: the outcome of a run swings with the seed (issue 9's target is ATE <= 2 % on every seed)."""
    if ctx.quick:
        return {"skipped": "full suite only (simulating takes minutes)"}
    import os

    import cv2

    from evpose.eval.slam_metrics import atlas_metrics, spread_summary
    from evpose.slam import SlamConfig, run_slam

    cv2.setNumThreads(1)
    load_before = os.getloadavg()[0]
    ate, tracked, visual, maps, cpu, rows = [], [], [], [], [], []
    for seed in range(ctx.seed, ctx.seed + LANDING_SEEDS):
        rec = _scenario_recording(ctx, "landing", seed)
        if rec is None:
            return {"skipped": "evpose.sim not available"}
        run = run_slam(rec, SlamConfig())
        m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s)
        ate.append(m.ate_percent)
        tracked.append(m.tracked_fraction)
        visual.append(run.visual_fraction)
        maps.append(len(m.maps))
        cpu.extend(r.timings_ms["mci_cpu"] + r.timings_ms["tracking_cpu"] for r in run.results)
        rows.append(f"s{seed} {m.ate_percent:.2f}% {len(m.maps)}m {100 * m.tracked_fraction:.0f}% (events {100 * run.visual_fraction:.0f}%)")
    out = {f"ate_percent_{k}": v for k, v in spread_summary(ate, 2.0).items()}
    out["tracked_fraction_min"] = float(min(tracked))
    out["visual_fraction_min"] = float(min(visual))
    out["maps_max"] = int(max(maps))
    out["per_mci_cpu_median_ms"] = float(np.median(cpu)) if cpu else float("nan")
    out["per_seed"] = "; ".join(rows)
    out["load_average_1min"] = float(max(load_before, os.getloadavg()[0]))
    return out


INERTIAL_SEEDS = 8
"""Simulator seeds per scenario of the event-inertial spread benchmark."""


def inertial_spread_summary(runs: list[tuple[int, float, float, bool]], trans_target: float = 0.01, rot_target: float = 0.01) -> dict:
    """Worst RPE, seeds within both targets and seeds never made metric, over ``(seed, RPE m/m, RPE deg/m, metric)`` runs."""
    t = np.array([r[1] for r in runs], np.float64)
    r = np.array([r[2] for r in runs], np.float64)
    within = np.isfinite(t) & np.isfinite(r) & (t <= trans_target) & (r <= rot_target)
    return {"rpe_trans_per_m_worst": float(np.max(t)) if t.size else float("nan"),
            "rpe_rot_deg_per_m_worst": float(np.max(r)) if r.size else float("nan"),
            "within_targets": int(within.sum()), "never_metric": int(sum(not x[3] for x in runs)),
            "per_seed": "; ".join(f"s{x[0]} {x[1]:.4f} m/m {x[2]:.4f} deg/m{'' if x[3] else ' (not metric)'}" for x in runs)}


def bench_inertial_seed_spread(ctx: BenchContext) -> dict:
    """E-I-C2 SLAM on the ``landing`` and ``indoor`` scenarios over ``INERTIAL_SEEDS`` simulator seeds each (3 s at 346x260,
    full suite only, recordings cached): the worst RPE per scenario against issue 9's targets (0.01 m/m, 0.01 deg/m),
    how many seeds meet both, and on how many the IMU initialisation never made a map metric. One seed per scenario
    (``scenario_*_c2``) hid that indoor seeds 3 and 7 miss the targets, seed 7 by running away (session 35)."""
    if ctx.quick:
        return {"skipped": "full suite only (simulating takes minutes)"}
    import cv2

    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.slam import SlamConfig, SlamMode, run_slam
    from evpose.slam.inertial import InertialConfiguration

    cv2.setNumThreads(1)
    cfg = SlamConfig()
    cfg.mode = SlamMode.EVENT_INERTIAL
    cfg.inertial.configuration = InertialConfiguration.C2
    out = {}
    for scenario in ("landing", "indoor"):
        runs = []
        for seed in range(ctx.seed, ctx.seed + INERTIAL_SEEDS):
            rec = _scenario_recording(ctx, scenario, seed)
            if rec is None:
                return {"skipped": "evpose.sim not available"}
            run = run_slam(rec, cfg)
            m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=False, duration_s=run.duration_s)
            metric = any(mp.imu_initialised for mp in run.atlas.maps if mp.traj_t)
            runs.append((seed, m.rpe_trans_per_m, m.rpe_rot_deg_per_m, metric))
        out.update({f"{scenario}_{k}": v for k, v in inertial_spread_summary(runs).items()})
    return out


BENCHMARKS = {
    "event_image": bench_event_image,
    "pipeline_synthetic": bench_pipeline_synthetic,
    "projection_search_ab": bench_projection_search_ab,
    "scenario_landing": bench_scenario,
    "scenario_landing_c2": _scenario_bench("landing", "c2"),
    "landing_seed_spread": bench_landing_seed_spread,
    "scenario_indoor": _scenario_bench("indoor", None),
    "scenario_indoor_c2": _scenario_bench("indoor", "c2"),
    "inertial_seed_spread": bench_inertial_seed_spread,
}
