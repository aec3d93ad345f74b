"""Fusion benchmarks that run the whole tracker on the simulated moderate landing (from ground truth).

* ``ablation``: stpe / stpe+filter / full / full with the EKF (paper Fig. 19):
  accuracy (and the factor graph's offline smoothed trajectory), latency per
  module and of the registration front end, share of events the polarity filter removes.
* ``ablation_texture``: the same on the textured landing (full suite), where the
  map explains few of the events, as in the paper's real scenes.
* ``ablation_seeds``: the four modes over several simulator seeds at both resolutions (means and per seed).
* ``ablation_long``: ``stpe`` / ``full`` / ``full`` with the EKF over several 3 s landings at 346x260.
* ``realtime_300hz``: ``full`` at 300 updates/s, whole session against the
  recording's duration (issue 7: sustains 300 Hz faster than real time).
* ``registration_wander``: why ``full`` stays near 9-10 mm: the registrations'
  errors and, on the same recorded inputs, online / smoothed / EKF / dead-reckoning estimates, and the online
  estimate fed only the slow or only the fast part of the registrations' errors.
* ``aligned_field``: ``T_align``'s distance field from its patch list against the
  image path, alternating in one process, outputs hashed.
* ``refinement_cost`` / ``crowding_cost``: per-update CPU with and without the painted-edge refinement / the
  crowded-point test, alternated in one process.

Registered under the ``fusion`` area by :mod:`evpose.bench.fusion`.
"""

from __future__ import annotations

import os
import time

import numpy as np

from evpose.bench.stats import latency_summary


def _timed_steps(session):
    """Step ``session`` to its end, yielding (step result, this thread's CPU time of the step in ms)."""
    while True:
        c0 = time.thread_time()
        r = session.step()
        if r is None:
            return
        yield r, (time.thread_time() - c0) * 1e3


def _load() -> dict:
    la = os.getloadavg()
    return {"load_avg_1min": float(la[0]), "cpus": os.cpu_count() or 0}


LATENCY_KEYS = ("median_ms", "p95_ms", "p99_ms")
"""The latency figures the tracking benchmarks report."""

ABLATION = (("stpe", "stpe", None), ("stpe+filter", "stpe+filter", None), ("stpe+filter_per_point_fields", "stpe+filter", False),
            ("full", "full", None), ("full_per_point_fields", "full", False), ("full_ekf", "full:ekf", None))
"""(name, mode[:fusion backend], polarity.event_filter override) of the ablation runs."""


def ablation_run(recording, contour_map, mode: str, event_filter: bool | None = None) -> dict:
    """One tracking run from ground truth: accuracy, losses, per-module latency and the polarity filter's counts.

    ``stpe_latency`` is the registration front end per update (distance field +
    polarity filter + registration, wall); ``stpe_latency_to_pose`` the same without the filter's labelling and
    sign learning (``polarity_observe``, after the pose is out); the filter's parts are ``polarity_predict`` /
    ``polarity_align`` / ``polarity_observe``; ``field_registration`` the field and the registration alone (the
    floor of a filter whose own stages cost nothing); ``events_removed_share`` is the share
    of the noise-filtered events entering the SP-TS that ``T_align`` does not show
    to registration (outside every map point's patch, or of the polarity the
    patch does not accept), summed over the run.
    """
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.fusion import FusionBackend
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession
    from evpose.tracker.step_result import TrackStatus

    name, _, backend = mode.partition(":")
    cfg = TrackerConfig(mode=TrackerMode(name))
    if backend:
        cfg.fusion.backend = FusionBackend(backend)
    if event_filter is not None:
        cfg.polarity.event_filter = bool(event_filter)
    session = TrackingSession(recording, contour_map, cfg)
    motion = session.tracker.components.motion
    smooth = name == "full" and cfg.fusion.backend is FusionBackend.FACTOR_GRAPH
    if smooth:  # record the fusion's inputs for the smoothed trajectory (after the run, off the latency figures)
        from evpose.fusion.replay import FusionInputs, smoothed_trajectory

        inputs = FusionInputs(int(motion.last.t_us), motion.last.T_world_cam.copy(), motion.initial_velocity_world)
        motion.input_log = inputs.reports
    cpu = [ms for _, ms in _timed_steps(session)]
    res = session.results
    out: dict = {"updates": len(res), "lost_updates": sum(r.status is not TrackStatus.OK for r in res)}
    traj = session.trajectory()
    if len(traj) >= 3:
        ev = evaluate(traj, recording.ground_truth, EvalConfig(align=Alignment.NONE))
        out["ate_rmse_mm"], out["are_rmse_deg"] = ev.ate["rmse"] * 1e3, ev.are["rmse"]
        if smooth:  # what only the graph can give: the trajectory smoothed over 400 states (2 s at 200 Hz), offline
            ev = evaluate(smoothed_trajectory(cfg.fusion, recording.calibration, recording.imu, inputs), recording.ground_truth,
                          EvalConfig(align=Alignment.NONE))
            out["smoothed_ate_rmse_mm"], out["smoothed_are_rmse_deg"] = ev.ate["rmse"] * 1e3, ev.are["rmse"]
    warm = res[5:] if len(res) > 10 else res
    for m in ("distance_field", "polarity_filter", "polarity_predict", "polarity_align", "polarity_observe", "registration", "fusion",
              "ego_motion", "culling", "total"):
        out.update({k: v for k, v in latency_summary([r.timings_ms[m] for r in warm if m in r.timings_ms], f"{m}_").items()
                    if k.endswith(LATENCY_KEYS)})
    stpe = [sum(r.timings_ms.get(m, 0.0) for m in ("distance_field", "polarity_filter", "registration")) for r in warm]
    out.update({k: v for k, v in latency_summary(stpe, "stpe_latency_").items() if k.endswith(LATENCY_KEYS + ("mean_ms",))})
    # The same without the filter's labelling and sign learning, which run after the pose is out (the pose's latency).
    to_pose = [sum(r.timings_ms.get(m, 0.0) for m in ("distance_field", "polarity_predict", "polarity_align", "registration")) for r in warm]
    out.update({k: v for k, v in latency_summary(to_pose, "stpe_latency_to_pose_").items() if k.endswith(LATENCY_KEYS)})
    # The field and the registration alone: what the front end would cost if the filter's own stages cost nothing.
    core = [sum(r.timings_ms.get(m, 0.0) for m in ("distance_field", "registration")) for r in warm]
    out.update({k: v for k, v in latency_summary(core, "field_registration_").items() if k.endswith(LATENCY_KEYS)})
    out.update({k: v for k, v in latency_summary(cpu[5:] if len(cpu) > 10 else cpu, "update_cpu_").items() if k.endswith(LATENCY_KEYS)})
    judged = sum(r.counts.get("events_polarity_judged", 0) for r in res)
    if judged:
        out["events_removed_share"] = sum(r.counts.get("events_polarity_removed", 0) for r in res) / judged
        out["events_outside_patches_share"] = sum(r.counts.get("events_outside_patches", 0) for r in res) / judged
        out["events_wrong_polarity_share"] = sum(r.counts.get("events_wrong_polarity", 0) for r in res) / judged
    used = sum(r.counts.get("points_used", 0) for r in res)
    if "points_single_polarity" in res[-1].counts and used:
        out["points_single_polarity_share"] = sum(r.counts.get("points_single_polarity", 0) for r in res) / used
    out["iterations_median"] = float(np.median([r.counts.get("iterations", 0) for r in res]))
    return out


def bench_ablation(ctx) -> dict:
    """EV-Pose ablation (paper Fig. 19) on the simulated moderate landing from ground truth, all runs in one process:
    stpe, stpe+filter, full, full with the EKF, and the filter's per-point-field variant (no T_align) for comparison."""
    from evpose.bench.tracking import landing_case

    res, seconds = ((240, 180), 1.0) if ctx.quick else ((346, 260), 2.0)
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    # The quick suite keeps to the four modes of the paper's figure.
    return _ablation_table(rec, cmap, f"{res[0]}x{res[1]}", seconds, with_variants=not ctx.quick)


def _ablation_table(rec, cmap, resolution: str, seconds: float, with_variants: bool) -> dict:
    """Every mode of ``ABLATION`` on one recording (the filter variants only ``with_variants``), one dict."""
    out: dict = {"resolution": resolution, "seconds": seconds, "map_points": len(cmap)}
    for name, mode, event_filter in ABLATION:
        if event_filter is None or with_variants:
            out.update({f"{name}_{k}": v for k, v in ablation_run(rec, cmap, mode, event_filter).items()})
    base = out.get("stpe_stpe_latency_median_ms")
    if base:
        out["filter_stpe_latency_change_pct"] = 100.0 * (out["stpe+filter_stpe_latency_median_ms"] - base) / base
        # Without the labelling after the pose, and the floor of any filter that registers the map's points: its field
        # and registration alone against stpe's whole front end (the target is -40 %).
        out["filter_stpe_latency_to_pose_change_pct"] = 100.0 * (out["stpe+filter_stpe_latency_to_pose_median_ms"] - base) / base
        out["filter_free_floor_change_pct"] = 100.0 * (out["stpe+filter_field_registration_median_ms"] - base) / base
    out.update(_load())
    return out


def bench_ablation_texture(ctx) -> dict:
    """The ablation on the textured landing (full suite only): the ground carries fine brightness texture that the
    map does not, as the paper's real scenes do, so most events near the ground are not the map's; stpe, stpe+filter,
    full and full with the EKF, at 346x260 for 2 s."""
    from evpose.bench.tracking import landing_case

    if ctx.quick:
        return {"skipped": "full suite only (rendering the texture takes minutes)"}
    rec, cmap = landing_case(ctx.work_dir, (346, 260), 2.0, ctx.seed, scenario="landing_texture")
    return _ablation_table(rec, cmap, "346x260", 2.0, with_variants=False)


ABLATION_SEEDS = 4
"""Simulator seeds of ``ablation_seeds`` (one seed's figures move by several mm with the scene's noise)."""


def bench_ablation_seeds(ctx) -> dict:
    """The four modes of the paper's ablation over ``ABLATION_SEEDS`` simulated 2 s landings at 346x260 and 240x180
    (full suite only): ATE/ARE (RMSE) per seed and their means, the factor graph's smoothed ATE, updates not OK."""
    if ctx.quick:
        return {"skipped": "full suite only (simulating 8 recordings takes minutes)"}
    out: dict = {}
    for res in ((346, 260), (240, 180)):
        out.update(_seed_table(ctx, res, 2.0, f"{res[0]}x{res[1]}", [name for name, _, f in ABLATION if f is None]))
    out.update(_load())
    return out


LONG_MODES = ("stpe", "full", "full_ekf")
"""Modes of ``ablation_long``."""


def bench_ablation_long(ctx) -> dict:
    """``stpe``, ``full`` and ``full`` with the EKF over ``ABLATION_SEEDS`` simulated 3 s landings at 346x260 (full
    suite only). The fusion's bias priors that helped the 2 s landings made 3 s flights worse (session 14,
    ``FusionConfig.init_sigma_acc_bias_vertical``): defaults are judged on both."""
    if ctx.quick:
        return {"skipped": "full suite only (simulating four 3 s recordings takes minutes)"}
    out = _seed_table(ctx, (346, 260), 3.0, "346x260_3s", list(LONG_MODES))
    out.update(_load())
    return out


def _seed_table(ctx, res: tuple[int, int], seconds: float, tag: str, names: list[str]) -> dict:
    """The ``ABLATION`` runs ``names`` on ``ABLATION_SEEDS`` simulated landings: per-seed ATE/ARE and means."""
    from evpose.bench.tracking import landing_case

    modes = {name: mode for name, mode, event_filter in ABLATION if event_filter is None}
    runs = {name: [] for name in names}
    for seed in range(ctx.seed, ctx.seed + ABLATION_SEEDS):
        case = landing_case(ctx.work_dir, res, seconds, seed)
        for name in names:
            runs[name].append(ablation_run(*case, modes[name]))
    out: dict = {}
    for name, per in runs.items():
        for key in ("ate_rmse_mm", "are_rmse_deg", "smoothed_ate_rmse_mm"):
            vals = [r[key] for r in per if key in r]
            if vals:
                out[f"{tag}_{name}_{key}_per_seed"] = [round(v, 4) for v in vals]
                out[f"{tag}_{name}_{key}_mean"] = float(np.mean(vals))
        out[f"{tag}_{name}_not_ok_updates"] = sum(r["lost_updates"] for r in per)
    return out


def bench_realtime_300hz(ctx) -> dict:
    """``full`` at 300 updates per second of recording, whole session (ingest, front end, registration, fusion):
    wall and CPU time against the recording's duration (a real-time factor > 1 is faster than real time), per-update
    wall latency, and accuracy."""
    from evpose.bench.tracking import landing_case
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    res, seconds = ((240, 180), 1.0) if ctx.quick else ((346, 260), 2.0)
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    session = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL, rate_hz=300.0))
    for _ in range(5):  # first updates load the compiled kernels; time the steady state from here
        session.step()
    t_first = int(session.results[-1].t_us)
    w0, c0 = time.perf_counter(), time.process_time()
    session.run()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    res_ = session.results
    span_s = (int(res_[-1].t_us) - t_first) / 1e6
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "updates": len(res_), "tracked_span_s": span_s, "wall_s": wall, "cpu_s": cpu,
                 "realtime_factor_wall": span_s / wall, "realtime_factor_cpu": span_s / cpu}
    out.update({k: v for k, v in latency_summary([r.timings_ms["total"] for r in res_[5:]], "total_").items()
                if k.endswith(LATENCY_KEYS)})
    ev = evaluate(session.trajectory(), rec.ground_truth, EvalConfig(align=Alignment.NONE))
    out["ate_rmse_mm"], out["are_rmse_deg"] = ev.ate["rmse"] * 1e3, ev.are["rmse"]
    out.update(_load())
    return out


def bench_registration_wander(ctx) -> dict:
    """Why ``full`` stays near 9-10 mm (issue 7; 16-18 mm in earlier sessions): the registrations' errors on the
    simulated moderate landing (:func:`~evpose.fusion.registration_errors.analyse_registration_errors`: calibration,
    time correlation, tilt/shift coupling), and on the same recorded inputs the online, fixed-lag and batch smoothed
    estimates, the EKF, and IMU dead reckoning with the simulator's true biases
    (:func:`~evpose.fusion.replay.fusion_error_study`); the online estimate on registrations carrying only the slow or
    only the fast part of their errors (:func:`~evpose.fusion.replay.error_band_study`)."""
    from evpose.bench.tracking import landing_case
    from evpose.fusion.registration_errors import analyse_registration_errors, ate_are, pose_error_vectors
    from evpose.fusion import FusionConfig
    from evpose.fusion.replay import FusionInputs, error_band_study, fusion_error_study
    from evpose.sim import SimulationConfig
    from evpose.sim.cache import load_or_simulate
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    res, seconds = ((240, 180), 1.0) if ctx.quick else ((346, 260), 2.0)
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    session = TrackingSession(rec, cmap, TrackerConfig(mode=TrackerMode.FULL))
    motion = session.tracker.components.motion
    inputs = FusionInputs(int(motion.last.t_us), motion.last.T_world_cam.copy(), motion.initial_velocity_world)
    motion.input_log = inputs.reports
    session.run()
    regs = [(t, T, c) for t, T, c in inputs.reports if T is not None and c is not None]
    errors = pose_error_vectors(np.array([r[0] for r in regs], np.int64), np.array([r[1] for r in regs]), rec.ground_truth)
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "seconds": seconds, **_load()}
    out.update(analyse_registration_errors(errors, np.array([r[2] for r in regs])))
    traj = session.trajectory()
    out["full_online_ate_mm"], out["full_online_are_deg"] = ate_are(traj.t, traj.matrices(), rec.ground_truth)
    truth = load_or_simulate(SimulationConfig(scenario="landing", seconds=seconds, resolution=res, seed=ctx.seed),
                             ctx.work_dir / "tracking" / "sim").imu_truth
    i0 = int(np.searchsorted(truth.samples.t, inputs.t0_us))
    out.update(fusion_error_study(rec.calibration, rec.imu, inputs, rec.ground_truth, (truth.acc_bias[i0], truth.gyro_bias[i0])))
    bands = error_band_study(FusionConfig(), rec.calibration, rec.imu, inputs, rec.ground_truth)
    out.update({f"error_band_{k}": v for k, v in bands.items()})
    return out


def _run_hashed(recording, contour_map, mode: str) -> tuple[str, list[float], dict]:
    """One run from ground truth: sha256 of every update's outputs, per-update CPU (ms) and per-module wall (ms)."""
    import hashlib

    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    session = TrackingSession(recording, contour_map, TrackerConfig(mode=TrackerMode(mode)))
    h, cpu, modules = hashlib.sha256(), [], {}
    for r, ms in _timed_steps(session):
        cpu.append(ms)
        for a in (r.pose, r.covariance, r.registration_pose, r.velocity):
            h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
        h.update(f"{r.status}{sorted(r.counts.items())}".encode())
        for k, v in r.timings_ms.items():
            modules.setdefault(k, []).append(v)
    return h.hexdigest(), cpu[5:], {k: v[5:] for k, v in modules.items()}


def bench_aligned_field(ctx) -> dict:
    """``T_align``'s distance field from its patch list (:mod:`evpose.fusion.aligned_field`) against ``compute`` over
    the composed image (the previous path) in ``full`` and ``stpe+filter`` on the simulated landing: the runs
    alternate old/new in one process (the machine is shared), every update's outputs are hashed (they must agree),
    and per-update CPU and per-module wall medians / p99 are reported per path."""
    from evpose.bench.tracking import landing_case
    from evpose.fusion import aligned_field

    res, seconds, rounds = ((240, 180), 1.0, 1) if ctx.quick else ((346, 260), 2.0, 2)
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    fill = aligned_field.fill_distance_field

    def image_path(aligned, field, t_us, roi=None, curvature=False):
        field.compute(aligned, t_us, (0,), roi, curvature)

    out: dict = {"resolution": f"{res[0]}x{res[1]}", "seconds": seconds, "rounds": rounds}
    for mode in ("full", "stpe+filter"):
        pooled: dict = {"image": ([], {}, set()), "patch_list": ([], {}, set())}
        for i in range(rounds):
            for path in (("image", "patch_list") if i % 2 == 0 else ("patch_list", "image")):
                aligned_field.fill_distance_field = fill if path == "patch_list" else image_path
                try:
                    digest, cpu, modules = _run_hashed(rec, cmap, mode)
                finally:
                    aligned_field.fill_distance_field = fill
                pooled[path][0].extend(cpu)
                for k, v in modules.items():
                    pooled[path][1].setdefault(k, []).extend(v)
                pooled[path][2].add(digest)
        for path, (cpu, modules, digests) in pooled.items():
            out.update({f"{mode}_{path}_{k}": v for k, v in latency_summary(cpu, "update_cpu_").items() if k.endswith(LATENCY_KEYS)})
            for m in ("polarity_filter", "distance_field", "registration"):
                out.update({f"{mode}_{path}_{k}": v for k, v in latency_summary(modules[m], f"{m}_").items() if k.endswith(LATENCY_KEYS)})
        out[f"{mode}_outputs_bit_identical"] = len(pooled["image"][2] | pooled["patch_list"][2]) == 1
    out.update(_load())
    return out


def bench_refinement_cost(ctx) -> dict:
    """Per-update CPU of ``stpe`` and ``full`` with and without the online painted-edge refinement
    (``map_refinement.enabled``), 2 s landing at 346x260 (1 s at 240x180 with ``quick``), the four runs alternated
    over rounds in one process so that the machine's phases hit both alike. ATE of each for reference."""

    def refine(cfg, on):
        cfg.map_refinement.enabled = on

    return _paired_cost(ctx, refine, ("unrefined", "refined"))


def bench_crowding_cost(ctx) -> dict:
    """As ``refinement_cost``, for the crowded-point test and the fused modes' per-point trail model together
    (``visible_map.crowded_radius_px``, ``registration.fused_lag_floor_px``, ``fused_polarity_trail_px`` and ``fused_buffer_trail_px`` 0 against
    their defaults): per-update CPU of ``stpe`` and ``full``, alternated in one process, ATE of each."""
    from evpose.tracker.registration_config import RegistrationConfig
    from evpose.tracker.visible_map import VisibleMapConfig

    radius, reg = VisibleMapConfig().crowded_radius_px, RegistrationConfig()

    def configure(cfg, on):
        cfg.visible_map.crowded_radius_px = radius if on else 0.0
        cfg.registration.fused_lag_floor_px = reg.fused_lag_floor_px if on else 0.0
        cfg.registration.fused_polarity_trail_px = reg.fused_polarity_trail_px if on else 0.0
        cfg.registration.fused_buffer_trail_px = reg.fused_buffer_trail_px if on else 0.0

    return _paired_cost(ctx, configure, ("all_points", "uncrowded"))


def _paired_cost(ctx, configure, labels: tuple[str, str]) -> dict:
    """Per-update CPU and ATE of ``stpe`` and ``full`` with ``configure(cfg, False)`` / ``(cfg, True)``, alternated."""
    from evpose.bench.tracking import landing_case
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    res, seconds, rounds = (((240, 180), 1.0, 1) if ctx.quick else ((346, 260), 2.0, 4))
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    cpu: dict[str, list[float]] = {}
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "rounds": rounds}
    for _ in range(rounds):
        for mode in ("stpe", "full"):
            for on in (False, True):
                cfg = TrackerConfig(mode=TrackerMode(mode))
                configure(cfg, on)
                session = TrackingSession(rec, cmap, cfg)
                key = f"{mode}_{labels[int(on)]}"
                cpu.setdefault(key, []).extend(ms for _, ms in list(_timed_steps(session))[5:])
                ev = evaluate(session.trajectory(), rec.ground_truth, EvalConfig(align=Alignment.NONE))
                out[f"{key}_ate_rmse_mm"] = float(ev.ate["rmse"] * 1e3)
    for key, samples in cpu.items():
        out.update({k: v for k, v in latency_summary(samples, f"{key}_update_cpu_").items() if k.endswith(LATENCY_KEYS)})
    out.update(_load())
    return out
