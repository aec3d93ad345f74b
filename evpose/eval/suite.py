"""The benchmark suite: studies shaped like the EV-Pose paper's Table I and Figs. 15-20, as (scenario, mode, rate) jobs.

Phase 1 simulates each needed scenario once (cached on disk); phase 2 runs one
tracking job per unique (scenario, mode, rate) — a study that shares a run with
another (the moderate-speed full-mode run at 200 Hz appears in five) reuses it.
Then the registered micro-benchmarks and, if dv-processing is installed, the peer
comparison run. Every job goes through :func:`evpose.eval.runner.run_jobs`, so the
suite runs on the local pool or on Dask and resumes after an interruption.
"""

from __future__ import annotations

import enum
import resource
import time
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from evpose.eval.cache import Job
from evpose.eval.scenarios import ScenarioSpec

MODES = ("stpe", "stpe+filter", "full", "ekf", "imu-only")
"""Every mode the suite knows; a mode the tracker does not offer yet is reported as not available."""

SLAM_MODES = {"slam-event": "event", "slam-event-inertial": "event-inertial"}
"""Suite modes that run map-free SLAM (``evpose.slam``, ``SlamMode`` values) instead of map-based tracking; they have no rate."""


class SuiteName(str, enum.Enum):
    QUICK = "quick"
    """Small sensor, short flights, the studies that share the landing scene: < 5 min here."""
    FULL = "full"
    """DAVIS346-sized sensor, 2 s flights, every study: what a release quotes."""


@dataclass(frozen=True)
class Study:
    """One table of the report: a set of runs that differ in one factor."""

    name: str
    title: str
    """Heading in the report, naming the paper's figure/table it mirrors."""
    scenarios: tuple[str, ...]
    modes: tuple[str, ...]
    rates_hz: tuple[float, ...]


@dataclass(frozen=True)
class SuiteConfig:
    """What one suite runs."""

    width: int = 240
    """Simulated sensor width, pixels."""
    height: int = 180
    """Simulated sensor height, pixels."""
    seconds: float = 0.5
    """Simulated flight duration per scenario, seconds."""
    seed: int = 0
    """Simulator seed."""
    studies: tuple[Study, ...] = ()
    cloud_density_per_m2: float = 100.0
    """Density of the simulated raw cloud behind each contour map, points per square metre."""


_ABLATION = Study("ablation", "Module ablation (paper Fig. 19)", ("landing",), ("stpe", "stpe+filter", "full"), (200.0,))
_FUSION = Study("fusion", "Fusion frameworks (paper Fig. 20)", ("landing",), ("full", "ekf", "imu-only"), (200.0,))
_FREQ = Study("frequency", "Estimation frequency (paper Fig. 16)", ("landing",), ("full",), (100.0, 200.0, 300.0))
_VEL = Study("velocity", "Drone velocity (paper Fig. 15)", ("landing_slow", "landing", "landing_fast"), ("full",), (200.0,))
_VEL_FULL = Study("velocity", "Drone velocity (paper Fig. 15)", ("landing_slow", "landing", "landing_fast", "landing_rotation"), ("full",), (200.0,))
_HDR = Study("hdr", "HDR (paper Fig. 17)", ("landing", "landing_hdr", "landing_flicker"), ("full",), (200.0,))
_DYN = Study("dynamics", "Scene dynamics (paper Fig. 18)", ("landing", "landing_dynamic", "landing_noisy"), ("full", "stpe+filter"), (200.0,))
_SYSTEMS = Study("systems", "Latency of the systems (paper Table I)", ("landing",), MODES, (200.0,))
_SLAM = Study("slam", "Event-based SLAM without a map (SLAM paper Table I: RPE per metre, stability)", ("landing_slow", "landing"), tuple(SLAM_MODES), (0.0,))
_SLAM_QUICK = replace(_SLAM, scenarios=("landing",))
"""About 1 s per mode on the quick suite's 0.5 s landing flight, which the other studies simulate anyway."""

SUITES: dict[SuiteName, SuiteConfig] = {
    SuiteName.QUICK: SuiteConfig(240, 180, 0.5, 0, (_SYSTEMS, _ABLATION, _FUSION, _FREQ, _VEL, _SLAM_QUICK)),
    SuiteName.FULL: SuiteConfig(346, 260, 2.0, 0, (_SYSTEMS, _ABLATION, _FUSION, _FREQ, _VEL_FULL, _HDR, _DYN, _SLAM)),
}


def scenario_specs(cfg: SuiteConfig) -> list[ScenarioSpec]:
    names = sorted({s for st in cfg.studies for s in st.scenarios})
    return [ScenarioSpec(n, cfg.seconds, cfg.width, cfg.height, cfg.seed, cfg.cloud_density_per_m2) for n in names]


def run_keys(cfg: SuiteConfig) -> list[tuple[str, str, float]]:
    """Unique (scenario, mode, rate) triples in a stable order."""
    seen: dict[tuple[str, str, float], None] = {}
    for st in cfg.studies:
        for s in st.scenarios:
            for m in st.modes:
                for r in st.rates_hz:
                    seen[(s, m, float(r))] = None
    return list(seen)


def run_name(scenario: str, mode: str, rate: float) -> str:
    # SLAM runs (rate 0) make an MCI whenever the adaptive event window fills: they have no rate.
    return f"{scenario}/{mode}" if mode in SLAM_MODES else f"{scenario}/{mode}/{rate:g}hz"


def simulation_jobs(cfg: SuiteConfig, cache_dir: str) -> list[Job]:
    return [Job(f"simulate/{s.scenario}", "evpose.eval.suite:simulate_job", {"spec": asdict(s), "cache_dir": cache_dir}) for s in scenario_specs(cfg)]


def tracking_jobs(cfg: SuiteConfig, cache_dir: str) -> list[Job]:
    out = []
    for scenario, mode, rate in run_keys(cfg):
        spec = ScenarioSpec(scenario, cfg.seconds, cfg.width, cfg.height, cfg.seed, cfg.cloud_density_per_m2)
        if mode in SLAM_MODES:
            out.append(Job(run_name(scenario, mode, rate), "evpose.eval.suite:scenario_slam_job", {"spec": asdict(spec), "mode": mode, "cache_dir": cache_dir}))
            continue
        out.append(Job(run_name(scenario, mode, rate), "evpose.eval.suite:scenario_tracking_job", {"spec": asdict(spec), "mode": mode, "rate_hz": rate, "cache_dir": cache_dir}))
    return out


# ---------------------------------------------------------------- job functions


def simulate_job(spec: dict, cache_dir: str) -> dict:
    """Make sure one scenario's recording and map are cached (phase 1)."""
    from evpose.eval.scenarios import ensure_scenario

    rec, cmap, spent = ensure_scenario(ScenarioSpec(**spec), cache_dir)
    return {"metrics": {"recording": rec.name, "map": cmap.name}, "timing": {"generate_s": spent}}


FUSION_BASELINES = {"ekf": "ekf", "imu-only": "imu_only"}
"""Suite modes that are the full pipeline with another fusion backend (``FusionConfig.backend`` values)."""


def _tracker_config(mode: str | None, rate_hz: float, base: dict | None = None):
    """TrackerConfig for a suite mode: a ``TrackerMode`` value, or a fusion baseline (full mode, other backend)."""
    from evpose.errors import ConfigError, InputError
    from evpose.tracker.config import TrackerConfig, TrackerMode, config_from_dict

    data = dict(base or {})
    if mode is not None:
        known = [m.value for m in TrackerMode]
        data["rate_hz"] = float(rate_hz)
        if mode in FUSION_BASELINES:
            data["mode"] = TrackerMode.FULL.value
            data["fusion"] = {"backend": FUSION_BASELINES[mode]}
        elif mode in known:
            data["mode"] = mode
        else:
            raise ConfigError(f"mode {mode!r} is not available in this build (tracker modes: {', '.join(known)})")
    try:
        return config_from_dict(TrackerConfig, data, source="tracker config")
    except InputError as exc:
        if mode in FUSION_BASELINES:
            # Until the tracker composes a FusionConfig, the baselines cannot be selected.
            raise ConfigError(f"mode {mode!r} is not available in this build (TrackerConfig has no fusion.backend: {exc})") from None
        raise


def track_and_measure(recording, contour_map, config) -> dict:
    """Run a TrackingSession to the end; accuracy (deterministic) and latency/resources (measured)."""
    from evpose.bench.stats import latency_summary
    from evpose.errors import InputError
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.eval.speed_bins import speed_bins
    from evpose.tracker.session import TrackingSession

    ru0 = resource.getrusage(resource.RUSAGE_SELF)
    w0 = time.perf_counter()
    session = TrackingSession(recording, contour_map, config)
    setup_s = time.perf_counter() - w0
    results = []
    step_s = []
    t0 = time.perf_counter()
    while True:
        ts = time.perf_counter()
        r = session.step()
        if r is None:
            break
        step_s.append(time.perf_counter() - ts)
        results.append(r)
    loop_s = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_SELF)
    # The first step of a fresh process loads (or compiles) the numba kernels: keep it out of the
    # latency and rate figures and report it on its own.
    warm = results[1:] if len(results) > 1 else results
    warm_s = float(sum(step_s[1:])) if len(step_s) > 1 else loop_s

    statuses = [r.status.value for r in results]
    n = len(results)
    events_in = int(sum(r.counts.get("events_in", 0) for r in results))
    events_kept = int(sum(r.counts.get("events_kept", r.counts.get("events_in", 0)) for r in results))
    metrics: dict = {
        "steps": n,
        "status_share": {s: statuses.count(s) / n for s in sorted(set(statuses))} if n else {},
        "events_in": events_in,
        "events_kept": events_kept,
        "filtered_share": 1.0 - events_kept / events_in if events_in else 0.0,
        "points_used_mean": float(np.mean([r.counts.get("points_used", 0) for r in results])) if n else 0.0,
    }
    gt = recording.ground_truth
    try:
        # Map-based tracking estimates poses in the map's (= ground truth's) world frame, so the
        # headline figures need no alignment; an SE(3) Umeyama fit on a short, nearly straight
        # flight is ill-conditioned in rotation and would inflate ARE. SE(3)-aligned figures
        # (the paper's evo convention) are kept alongside.
        res = evaluate(session.trajectory(), gt, EvalConfig(align=Alignment.NONE))
        res_se3 = evaluate(session.trajectory(), gt, EvalConfig(align=Alignment.SE3))
        metrics["accuracy"] = {**res.summary(), "speed_bins": speed_bins(res, gt), "ate_se3_m": res_se3.ate, "are_se3_deg": res_se3.are}
        metrics["accuracy"].pop("alignment_sim3")
    except InputError as exc:
        metrics["accuracy"] = {"error": str(exc)}

    modules = sorted({k for r in warm for k in r.timings_ms})
    latency = {k: latency_summary([r.timings_ms[k] for r in warm if k in r.timings_ms]) for k in modules}
    warm_events = sum(r.counts.get("events_in", 0) for r in warm)
    cpu_s = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    timing = {
        "latency_ms": latency,
        "first_step_ms": step_s[0] * 1e3 if step_s else 0.0,
        "setup_s": setup_s,
        "loop_s": loop_s,
        "updates_per_s": len(warm) / warm_s if warm_s > 0 else 0.0,
        "event_throughput_mev_s": warm_events / warm_s / 1e6 if warm_s > 0 else 0.0,
        "cpu_percent": 100.0 * cpu_s / loop_s if loop_s > 0 else 0.0,
        "peak_rss_mb": ru1.ru_maxrss / 1024.0,
    }
    return {"metrics": metrics, "timing": timing}


def scenario_tracking_job(spec: dict, mode: str, rate_hz: float, cache_dir: str) -> dict:
    """One benchmark run: a cached simulated scenario tracked in ``mode`` at ``rate_hz`` (phase 2)."""
    from evpose.eval.scenarios import load_scenario

    config = _tracker_config(mode, rate_hz)
    sc = load_scenario(ScenarioSpec(**spec), cache_dir)
    return track_and_measure(sc.recording, sc.contour_map, config)


def slam_and_measure(recording, mode: str) -> dict:
    """Run map-free SLAM (``evpose.slam.run_slam``) over a recording: the SLAM paper's metrics (deterministic) and per-MCI latency (measured)."""
    from collections import Counter

    import cv2

    from evpose.bench.stats import latency_summary
    from evpose.errors import ConfigError
    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.slam import SlamConfig, SlamMode, run_slam

    if mode not in SLAM_MODES:
        raise ConfigError(f"SLAM mode {mode!r} is unknown (known: {', '.join(SLAM_MODES)})")
    slam_mode = SlamMode(SLAM_MODES[mode])
    # One OpenCV thread, as ``evpose slam`` does: the per-stage CPU timings then cover all the work.
    cv2.setNumThreads(1)
    ru0 = resource.getrusage(resource.RUSAGE_SELF)
    run = run_slam(recording, SlamConfig(mode=slam_mode))
    ru1 = resource.getrusage(resource.RUSAGE_SELF)
    res = run.results
    n = len(res)
    statuses = Counter(r.status.value for r in res)
    metrics: dict = {
        "mcis": n,
        "status_share": {k: v / n for k, v in sorted(statuses.items())} if n else {},
        "hypothesis_counts": dict(sorted(Counter(r.hypothesis for r in res if r.hypothesis).items())),
        "atlas_maps": len([m for m in run.atlas.maps if m.traj_t]),
        "correct_scale": slam_mode is SlamMode.EVENT,
    }
    gt = recording.ground_truth
    trajs = run.trajectories()
    if gt is None or len(gt) < 2:
        metrics["slam"] = {"error": "the recording has no ground truth"}
    elif not trajs:
        reasons = Counter(r.reason for r in res if r.reason)
        metrics["slam"] = {"error": "not initialised: " + (reasons.most_common(1)[0][0] if reasons else "no MCI was produced")}
    else:
        # Event-only maps have no metric scale: Sim(3) alignment per map, as the paper does.
        metrics["slam"] = atlas_metrics(trajs, gt, correct_scale=slam_mode is SlamMode.EVENT, duration_s=run.duration_s).to_dict()
        metrics["slam"]["visual_fraction"] = run.visual_fraction
    # The first MCI of a fresh process loads (or compiles) the numba kernels: reported apart.
    warm = res[1:] if n > 1 else res
    latency = {k: latency_summary([r.timings_ms[k] for r in warm if k in r.timings_ms]) for k in ("mci", "tracking", "total", "mci_cpu", "tracking_cpu")}
    cpu_s = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    timing = {
        "latency_ms": latency,
        "first_mci_ms": res[0].timings_ms.get("total", 0.0) if n else 0.0,
        "wall_s": run.wall_s,
        "realtime_factor": run.duration_s / run.wall_s if run.wall_s > 0 else 0.0,
        "cpu_percent": 100.0 * cpu_s / run.wall_s if run.wall_s > 0 else 0.0,
        "peak_rss_mb": ru1.ru_maxrss / 1024.0,
    }
    return {"metrics": metrics, "timing": timing}


def scenario_slam_job(spec: dict, mode: str, cache_dir: str) -> dict:
    """One SLAM benchmark run: a cached simulated scenario through ``evpose.slam`` in ``mode`` (``slam-event`` / ``slam-event-inertial``)."""
    from evpose.eval.scenarios import load_scenario

    sc = load_scenario(ScenarioSpec(**spec), cache_dir)
    return slam_and_measure(sc.recording, mode)


def tracking_job(config: dict, recording: str) -> dict:
    """Sweep job: a full TrackerConfig (nested dict) on a recording spec (``sim:NAME`` or ``REC::MAP``)."""
    from evpose.eval.recordings import load_map, load_recording

    cfg = _tracker_config(None, 0.0, config)  # type: ignore[arg-type]
    result = track_and_measure(load_recording(recording), load_map(recording), cfg)
    acc = result["metrics"].get("accuracy", {})
    # Flatten the figures a sweep ranks by; a run that cannot be evaluated scores +inf.
    flat = {
        "ate_mean_m": acc["ate_m"]["mean"] if "ate_m" in acc else float("inf"),
        "are_mean_deg": acc["are_deg"]["mean"] if "are_deg" in acc else float("inf"),
        "rte_mean_m": acc["rte_m"].get("mean", float("inf")) if "rte_m" in acc else float("inf"),
        "rre_mean_deg": acc["rre_deg"].get("mean", float("inf")) if "rre_deg" in acc else float("inf"),
        "ok_share": result["metrics"]["status_share"].get("ok", 0.0),
        "filtered_share": result["metrics"]["filtered_share"],
    }
    return {"metrics": flat, "timing": result["timing"]}


def micro_benchmark_job(name: str, quick: bool, work_dir: str, seed: int = 0) -> dict:
    """One registered micro-benchmark (``area.name`` from :func:`evpose.bench.collect`)."""
    from pathlib import Path

    from evpose.bench import BenchContext, collect

    fn = collect()[name]
    t0 = time.perf_counter()
    figures = fn(BenchContext(quick=quick, work_dir=Path(work_dir), seed=seed))
    # What each benchmark costs the suite, so its owner can see where the minutes go.
    return {"metrics": {}, "timing": {"bench_wall_s": time.perf_counter() - t0, **figures}}


@dataclass
class SuiteRun:
    """Everything the report needs."""

    suite: SuiteName
    config: SuiteConfig
    simulations: list[dict] = field(default_factory=list)
    runs: dict[str, dict] = field(default_factory=dict)
    """run name -> outcome (``ok``, ``result``/``error``, ``cached``)."""
    micro: dict[str, dict] = field(default_factory=dict)
    peers: dict | None = None
    wall_s: float = 0.0
    phases_s: dict[str, float] = field(default_factory=dict)
    """Wall time per phase (simulate, track, micro-benchmarks, peers), seconds."""
