"""Fusion benchmarks: per-update latency and accuracy of the backends, and the polarity filter on simulated data.

* ``backends``: an analytic flight with a realistic MEMS IMU (biases, noise)
  and noisy registrations at 300 Hz (5 mm / 0.3 deg, 2 % gross outliers). All
  backends run on the same inputs in the same process, so their latencies
  compare fairly even on a loaded machine. Reports per-update latency
  (median/p95/p99; wall time and this thread's CPU time, which a loaded
  machine inflates much less) for plain iSAM2 updates and for the updates
  that also run the window re-optimisation, ``predict`` and ``imu_rate_poses`` latency, and
  ATE/ARE (RMSE) of raw registrations, factor graph, EKF and IMU-only.
* ``ablation``, ``ablation_texture``, ``ablation_seeds``, ``ablation_long``, ``realtime_300hz``, ``registration_wander``, ``aligned_field``, ``refinement_cost``, ``crowding_cost``: whole tracking runs on
  the simulated landing, in :mod:`evpose.bench.fusion_tracking`.
* ``full_filter_cost`` (:mod:`evpose.bench.filter_registration_cost`): ``full`` with and without the polarity filter,
  alternated: the registration stages' CPU per update, the events they take, ATE (issue 7's -40 % read in ``full``).
* ``regimes`` (:mod:`evpose.bench.fusion_regimes`): the factor graph against the EKF, paired per seed, in a cold
  start (no initial velocity, the pose off) and across registration outages of 0.1-0.5 s.
* ``polarity_ceiling`` (:mod:`evpose.bench.polarity_ceiling`): the filter's wrong predictions on the
  simulated landing, with fused and true motion, and ``stpe+filter`` with oracle polarities.
* ``polarity_sim``: the simulator's landing scenario, a contour map built from
  its cloud, ground-truth poses and motion: agreement of the predicted polarity
  with the events near each point (outside the buffer zone), share of events
  and points the filter removes, prediction and ego-motion filter latency.
"""

from __future__ import annotations

import os
import time

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.bench.fusion_tracking import (ABLATION, ablation_run, bench_ablation, bench_ablation_long, bench_ablation_seeds, bench_ablation_texture,  # noqa: F401
                                          bench_aligned_field, bench_crowding_cost, bench_realtime_300hz, bench_refinement_cost,
                                          bench_registration_wander)
from evpose.bench.filter_registration_cost import bench_full_filter_cost
from evpose.bench.fusion_regimes import bench_fusion_regimes
from evpose.bench.polarity_ceiling import bench_polarity_ceiling
from evpose.bench.stats import latency_summary, peak_rss_mb


def _load() -> dict:
    la = os.getloadavg()
    return {"load_avg_1min": float(la[0]), "cpus": os.cpu_count() or 0}


def _errors(T_est: np.ndarray, T_gt: np.ndarray) -> tuple[float, float]:
    dt = float(np.linalg.norm(T_est[:3, 3] - T_gt[:3, 3]))
    dr = float(np.linalg.norm(Rotation.from_matrix(T_est[:3, :3].T @ T_gt[:3, :3]).as_rotvec()))
    return dt, dr


def _rmse(errs: list[tuple[float, float]]) -> tuple[float, float]:
    a = np.asarray(errs)
    return float(np.sqrt(np.mean(a[:, 0] ** 2)) * 1e3), float(np.degrees(np.sqrt(np.mean(a[:, 1] ** 2))))


def bench_backends(ctx) -> dict:
    from evpose.core.camera import CameraCalibration
    from evpose.fusion import FusionBackend, FusionConfig, make_fusion
    from evpose.fusion.synthetic import AnalyticMotion, AnalyticMotionConfig, default_T_cam_imu

    seconds = 3.0 if ctx.quick else 10.0
    rate_hz = 300.0
    cal = CameraCalibration(346, 260, 300.0, 300.0, 172.5, 129.5, T_cam_imu=default_T_cam_imu())
    motion = AnalyticMotion(AnalyticMotionConfig(duration_s=seconds, imu_rate_hz=1000.0, acc_bias=(0.08, -0.05, 0.1),
                                                 gyro_bias=(0.01, -0.02, 0.015), accel_noise_density=2e-3,
                                                 gyro_noise_density=1.7e-4, seed=ctx.seed))
    imu = motion.imu()
    t0 = motion.config.t0_us
    times = t0 + np.round(np.arange(1, int(seconds * rate_hz)) * 1e6 / rate_hz).astype(np.int64)
    gt = motion.camera_trajectory(times, cal.T_cam_imu)
    rng = np.random.default_rng(ctx.seed + 1)
    st, sr = 0.005, np.radians(0.3)
    regs = []
    for k in range(len(gt)):
        T = gt.matrix(k)
        T[:3, :3] = T[:3, :3] @ Rotation.from_rotvec(rng.normal(0, sr, 3)).as_matrix()
        T[:3, 3] += T[:3, :3] @ rng.normal(0, st, 3)
        if rng.random() < 0.02:
            T[:3, 3] += rng.normal(0, 0.1, 3)
        regs.append(T)
    cov = np.diag([sr**2] * 3 + [st**2] * 3)
    skip = int(rate_hz)  # accuracy after the first second (bias convergence)
    out: dict = {"updates": len(times), "rate_hz": rate_hz, **_load()}
    out["registration_ate_mm"], out["registration_are_deg"] = _rmse([_errors(regs[k], gt.matrix(k)) for k in range(skip, len(gt))])

    # These registrations have white noise, so their covariance is taken as is (no scaling for correlated errors).
    white = {"registration_covariance_scale": 1.0}
    runs = [("factor_graph", FusionConfig(**white)), ("factor_graph_nocov", FusionConfig(compute_covariance=False, **white)),
            ("ekf", FusionConfig(backend=FusionBackend.EKF, **white)), ("imu_only", FusionConfig(backend=FusionBackend.IMU_ONLY, **white))]
    for name, cfg in runs:
        f = make_fusion(cfg, cal)
        f.add_imu(imu)
        f.initialize(int(t0), motion.camera_trajectory([t0], cal.T_cam_imu).matrix(0), motion.camera_velocity([t0], cal.T_cam_imu)[0])
        lat, cpu, errs, pred_lat, rate_lat = [], [], [], [], []
        for k, t in enumerate(times):
            a, c = time.perf_counter(), time.thread_time()
            s = f.update(int(t), regs[k], cov)
            lat.append((time.perf_counter() - a) * 1e3)
            cpu.append((time.thread_time() - c) * 1e3)
            errs.append(_errors(s.T_world_cam, gt.matrix(k)))
            a = time.perf_counter()
            f.predict(int(t) + 1000)
            pred_lat.append((time.perf_counter() - a) * 1e3)
            if k:
                a = time.perf_counter()
                f.imu_rate_poses(int(times[k - 1]), int(t))
                rate_lat.append((time.perf_counter() - a) * 1e3)
        lat = np.asarray(lat)
        out[f"{name}_ate_mm"], out[f"{name}_are_deg"] = _rmse(errs[skip:])
        out.update(latency_summary(lat, f"{name}_update_"))
        # CPU time of this thread: what the update costs without the waiting a loaded machine adds to wall time.
        out.update({k: v for k, v in latency_summary(cpu, f"{name}_update_cpu_").items() if not k.endswith("_n")})
        out.update({k: v for k, v in latency_summary(pred_lat, f"{name}_predict_").items() if not k.endswith("_n")})
        out.update({k: v for k, v in latency_summary(rate_lat, f"{name}_imu_rate_poses_").items() if not k.endswith("_n")})
        if name == "factor_graph":
            k_every = cfg.reoptimize_every
            joint = np.arange(1, len(lat) + 1) % k_every == 0
            cpu = np.asarray(cpu)
            out.update({k: v for k, v in latency_summary(cpu[~joint], "factor_graph_isam2_only_cpu_").items() if not k.endswith("_n")})
            out.update({k: v for k, v in latency_summary(cpu[joint], "factor_graph_with_window_reopt_cpu_").items() if not k.endswith("_n")})
            out["factor_graph_gyro_bias_error_pct"] = float(100 * np.linalg.norm(s.gyro_bias - np.array(motion.config.gyro_bias))
                                                           / np.linalg.norm(motion.config.gyro_bias))
    out["updates_per_s_factor_graph"] = float(1e3 / out["factor_graph_update_mean_ms"])
    out["peak_rss_mb"] = peak_rss_mb()
    return out


def _sim_motion(traj, cal, t_us: int):
    ts = np.array([t_us * 1e-6])
    T = traj.camera_poses(ts)[0]
    wb = traj.body_rates(ts)[0]
    lever = np.linalg.inv(cal.T_cam_imu)[:3, 3]
    v_cam = traj.body_velocity(ts)[0] + traj.body_rotation(ts).apply(np.cross(wb, lever))[0]
    return T, cal.T_cam_imu[:3, :3] @ wb, v_cam


def _polarity_run(rec, traj, cmap, learn: bool, seconds: float, ego=None) -> dict:
    """Predict per step (300 Hz) at the true pose and motion; optionally learn signs online; score the second half."""
    from evpose.fusion import PolarityFilterConfig, PolarityPredictor, classify_events, filter_summary, observed_point_polarity
    from evpose.tracker.visible_map import VisibleMapConfig, visible_points

    cal = rec.calibration
    K = cal.K
    pred = PolarityPredictor(PolarityFilterConfig(learned_overrides_map=learn))
    step_us = 3333
    t_score = int(seconds * 1e6) // 2
    agree = judged = pts_single = pts_total = ego_removed = ego_total = 0
    labels, pred_ms, ego_ms = [], [], []
    for t1 in range(20_000, int(seconds * 1e6), step_us):
        ev = rec.events.time_window(t1 - step_us, t1)
        T, omega_cam, v_cam = _sim_motion(traj, cal, t1)
        vis = visible_points(cmap.points, T, K, cal.width, cal.height, VisibleMapConfig())
        a = time.perf_counter()
        pol = pred.predict(cmap.points[vis], cmap.edge_normal[vis], cmap.brightness_sign[vis], T, omega_cam, v_cam, K, vis)
        pred_ms.append((time.perf_counter() - a) * 1e3)
        X = (cmap.points[vis] - T[:3, 3]) @ T[:3, :3]
        uv = np.stack([K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]], 1)
        label, point = classify_events(ev.x, ev.y, ev.p, uv, pol, pred.config.patch_radius_px, cal.width, cal.height)
        if learn:
            pred.learn(vis, observed_point_polarity(point, ev.p, vis.size))
        if ego is not None:
            win = rec.events.time_window(t1 - 20_000, t1)
            a = time.perf_counter()
            keep = ego.filter(win.x, win.y, win.t, T, omega_cam, v_cam, K, cal.width, cal.height, cmap.points[vis], t_ref_us=t1)
            ego_ms.append((time.perf_counter() - a) * 1e3)
            ego_removed += int(np.count_nonzero(~keep[win.t >= t1 - step_us]))
            ego_total += int(np.count_nonzero(win.t >= t1 - step_us))
        if t1 < t_score:
            continue
        j = (point >= 0) & (pol[np.maximum(point, 0)] != 0)
        agree += int(np.count_nonzero(j & (label == 1)))
        judged += int(np.count_nonzero(j))
        labels.append(label)
        pts_single += int(np.count_nonzero(pol))
        pts_total += int(pol.size)
    summary = filter_summary(np.concatenate(labels)) if labels else filter_summary(np.zeros(0, np.int8))
    out = {"agreement_outside_buffer": agree / judged if judged else float("nan"), "events_judged": judged,
           "events_in_patches_share": summary["events_in_patches"] / summary["events"] if summary["events"] else 0.0,
           "events_removed_share_of_patches": summary["removed_share_of_patches"],
           "events_removed_share_of_all": summary["removed_share_of_all"],
           "points_single_polarity_share": pts_single / pts_total if pts_total else 0.0}
    out.update(latency_summary(pred_ms, "predict_"))
    if ego is not None:
        out["ego_motion_removed_share"] = ego_removed / ego_total if ego_total else 0.0
        out.update({k: v for k, v in latency_summary(ego_ms, "ego_motion_20ms_window_").items() if not k.endswith("_n")})
    return out


def bench_polarity_sim(ctx) -> dict:
    """Polarity filter (map signs vs online-learned signs) and ego-motion filter on the simulated landing."""
    from evpose.fusion import EgoMotionConfig, EgoMotionFilter
    from evpose.mapping import build_contour_map
    from evpose.sim import SimulationConfig, simulate

    seconds, res = (0.3, (240, 180)) if ctx.quick else (1.0, (346, 260))
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "seconds": seconds}
    scenarios = ("landing",) if ctx.quick else ("landing", "landing_dynamic")
    for name in scenarios:
        wall = time.perf_counter()
        sim = simulate(SimulationConfig(scenario=name, seconds=seconds, resolution=res, seed=ctx.seed))
        out[f"{name}_sim_s"] = time.perf_counter() - wall
        wall = time.perf_counter()
        cmap = build_contour_map(sim.cloud_points, intensity=sim.cloud_intensity)
        out[f"{name}_map_s"] = time.perf_counter() - wall
        out[f"{name}_map_points"] = len(cmap)
        out[f"{name}_map_points_with_sign_share"] = float(np.mean(cmap.brightness_sign != 0))
        for learn in (False, True):
            tag = f"{name}_{'learned' if learn else 'map'}_signs_"
            ego = EgoMotionFilter(EgoMotionConfig(enabled=True)) if learn else None
            run = _polarity_run(sim.recording, sim.trajectory, cmap, learn, seconds, ego=ego)
            out.update({tag + k: v for k, v in run.items()})
    out.update(_load())
    out["peak_rss_mb"] = peak_rss_mb()
    return out


def _moving_object_mask(scene, T_world_cam: np.ndarray, K: np.ndarray, t_s: float, width: int, height: int) -> np.ndarray:
    """Pixels covered by the convex hulls of the scene's moving objects (dilated 2 px), bool (H, W)."""
    import cv2

    m = np.zeros((height, width), np.uint8)
    for ob in scene.dynamic:
        P = (ob.pose(t_s) @ np.c_[ob.mesh.vertices, np.ones(len(ob.mesh.vertices))].T).T[:, :3]
        X = (P - T_world_cam[:3, 3]) @ T_world_cam[:3, :3]
        if np.allclose(ob.pose(t_s), ob.pose(t_s + 0.01)) or np.any(X[:, 2] <= 0.05):
            continue  # still objects (the fan's pole) are static structure, merely absent from the map
        uv = np.stack([K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]], 1)
        cv2.fillConvexPoly(m, cv2.convexHull(uv.astype(np.float32)).astype(np.int32), 1)
    return cv2.dilate(m, np.ones((5, 5), np.uint8)).astype(bool)


def bench_ego_motion_dynamic(ctx) -> dict:
    """Ego-motion filter on the dynamic-object scenario: kept share of events inside moving-object hulls vs elsewhere.

    The moving objects enter the view after ~1 s of the landing flight, so this
    needs a longer simulation (full suite only). Hull masks include some
    background between the fan blades, so the 'dynamic' share is a lower bound
    of what the filter removes from the objects themselves.
    """
    if ctx.quick:
        return {"skipped": "full suite only (the moving objects enter the view after ~1 s of simulated flight)"}
    from evpose.fusion import EgoMotionConfig, EgoMotionFilter
    from evpose.mapping import build_contour_map
    from evpose.sim import SimulationConfig, simulate
    from evpose.tracker.visible_map import VisibleMapConfig, visible_points

    seconds, res = 3.5, (240, 180)
    sim = simulate(SimulationConfig(scenario="landing_dynamic", seconds=seconds, resolution=res, seed=ctx.seed))
    cmap = build_contour_map(sim.cloud_points, intensity=sim.cloud_intensity)
    rec, cal = sim.recording, sim.recording.calibration
    K = cal.K
    out: dict = {"scenario": "landing_dynamic", "resolution": f"{res[0]}x{res[1]}", "seconds": seconds}
    for window_us in (20_000, 50_000):
        ego = EgoMotionFilter(EgoMotionConfig(enabled=True))
        kd = nd = ks = ns = 0
        ms = []
        for t1 in range(1_000_000, int(seconds * 1e6), 3 * 3333):
            T, omega_cam, v_cam = _sim_motion(sim.trajectory, cal, t1)
            vis = visible_points(cmap.points, T, K, cal.width, cal.height, VisibleMapConfig())
            win = rec.events.time_window(t1 - window_us, t1)
            a = time.perf_counter()
            keep = ego.filter(win.x, win.y, win.t, T, omega_cam, v_cam, K, cal.width, cal.height, cmap.points[vis], t_ref_us=t1)
            ms.append((time.perf_counter() - a) * 1e3)
            cur = win.t >= t1 - 3333
            dyn = _moving_object_mask(sim.scene, T, K, t1 * 1e-6, cal.width, cal.height)[win.y, win.x]
            kd += int(np.count_nonzero(keep & cur & dyn))
            nd += int(np.count_nonzero(cur & dyn))
            ks += int(np.count_nonzero(keep & cur & ~dyn))
            ns += int(np.count_nonzero(cur & ~dyn))
        tag = f"window_{window_us // 1000}ms_"
        out.update({tag + "moving_region_events": nd, tag + "moving_region_kept_share": kd / nd if nd else float("nan"),
                    tag + "elsewhere_events": ns, tag + "elsewhere_kept_share": ks / ns if ns else float("nan")})
        out.update({k: v for k, v in latency_summary(ms, tag + "filter_").items() if not k.endswith("_n")})
    out.update(_load())
    return out


def _same(a, b) -> bool:
    return (np.array_equal(a.T_world_cam, b.T_world_cam) and np.array_equal(a.velocity_world, b.velocity_world)
            and np.array_equal(a.gyro_bias, b.gyro_bias) and np.array_equal(a.acc_bias, b.acc_bias)
            and np.array_equal(a.covariance, b.covariance))


def bench_snapshot_restore(ctx) -> dict:
    """Factor-graph fusion snapshots (issue 7): cost of ``snapshot``/``restore`` against the step index.

    The fusion runs 200 Hz registrations of a 10 s flight (3 s quick) and takes a
    snapshot at a few steps; each is restored after the run and the next 20
    updates must equal the uninterrupted run bit for bit. Baseline in the same
    run: what restoring cost before, replaying every input since initialisation
    (``initialize`` + one ``update`` per step, the old ``restore``). Per-update
    CPU time is compared, updates interleaved, with gtsam's
    ``IncrementalFixedLagSmoother`` on the same inputs (estimates must be identical).
    """
    import gtsam

    from evpose.fusion import FusionConfig
    from evpose.fusion.factor_graph import FactorGraphFusion
    from evpose.fusion.synthetic import flight_with_registrations

    class NeverRebased(FactorGraphFusion):
        """Ours without its periodic re-base (``rebase_every_states``), which gtsam's smoother does not make."""

        rebase_every_states = 0

    class GtsamSmootherFusion(NeverRebased):
        """The same fusion on gtsam's own (uncopyable) fixed-lag smoother: the reference for estimates and cost."""

        def _new_smoother(self):
            s = super()._new_smoother()
            return gtsam.IncrementalFixedLagSmoother(s.lag, s.params)

    seconds, rate_hz = (3.0, 200.0) if ctx.quick else (10.0, 200.0)
    steps = (50, 300, 580) if ctx.quick else (50, 300, 1000, 2000)
    follow = 20
    cal, imu, first, times, regs, cov = flight_with_registrations(seconds + follow / rate_hz, rate_hz, ctx.seed)
    # gtsam's smoother's ordering, to compare; and no forced relinearisation, which gtsam's smoother cannot make
    cfg = FusionConfig(registration_covariance_scale=1.0, newest_state_last=False, relinearize_correction_velocity=0.0)

    def start(cls):
        f = cls(cfg, cal)
        f.add_imu(imu)
        f.initialize(*first)
        return f

    f, ref = start(NeverRebased), start(GtsamSmootherFusion)
    states, snaps, cpu_new, cpu_ref = [], {}, [], []
    snap_cpu, identical = {}, True
    for k, t in enumerate(times):
        for which in ((0, 1) if k % 2 else (1, 0)):  # alternate which runs first: no cache-order bias
            c = time.thread_time()
            if which == 0:
                s = f.update(int(t), regs[k], cov)
            else:
                r = ref.update(int(t), regs[k], cov)
            (cpu_new if which == 0 else cpu_ref).append((time.thread_time() - c) * 1e3)
        identical &= _same(s, r)
        states.append(s)
        if k + 1 in steps:
            c = time.thread_time()
            snaps[k + 1] = f.snapshot()
            snap_cpu[k + 1] = (time.thread_time() - c) * 1e3
    out: dict = {"updates": len(times), "rate_hz": rate_hz, "estimates_identical_to_gtsam_smoother": bool(identical), **_load()}
    warm = 20  # the first updates include numba's first-call compilation of the IMU integration
    out.update({k: v for k, v in latency_summary(cpu_new[warm:], "update_cpu_").items()})
    out.update({k: v for k, v in latency_summary(cpu_ref[warm:], "gtsam_smoother_update_cpu_").items() if not k.endswith("_n")})
    out["update_cpu_overhead_vs_gtsam_smoother_pct"] = 100.0 * (np.median(cpu_new[warm:]) / np.median(cpu_ref[warm:]) - 1.0)
    reproduced = True
    for step in steps:
        g = NeverRebased(cfg, cal)
        a, c = time.perf_counter(), time.thread_time()
        g.restore(snaps[step])
        out[f"restore_at_{step}_cpu_ms"] = (time.thread_time() - c) * 1e3
        out[f"restore_at_{step}_wall_ms"] = (time.perf_counter() - a) * 1e3
        out[f"snapshot_at_{step}_cpu_ms"] = snap_cpu[step]
        for k in range(step, min(step + follow, len(times))):
            reproduced &= _same(g.update(int(times[k]), regs[k], cov), states[k])
        # Before: restore replayed every input since initialisation.
        c = time.thread_time()
        h = NeverRebased(cfg, cal)
        h.add_imu(imu)
        h.initialize(*first)
        for k in range(step):
            h.update(int(times[k]), regs[k], cov)
        out[f"replay_restore_at_{step}_cpu_ms"] = (time.thread_time() - c) * 1e3
    out["restored_runs_bit_identical"] = bool(reproduced)
    out["peak_rss_mb"] = peak_rss_mb()
    return out


def bench_imu_buffer(ctx) -> dict:
    """IMU buffering per tracker update (issue 7): ``ImuBuffer.add`` of a 300 Hz step's samples from a 1 kHz IMU plus
    the ``pieces`` of its span, after 3 s, 1 min and 10 min of buffered samples (it must not grow with the run)."""
    from evpose.core.imu import ImuSamples
    from evpose.fusion.preintegration import ImuBuffer

    rng = np.random.default_rng(ctx.seed)
    out = {"load_average_1min": os.getloadavg()[0]}
    for label, minutes in (("3s", 0.05), ("1min", 1.0)) + ((() if ctx.quick else (("10min", 10.0),))):
        n = int(minutes * 60_000)
        t = np.arange(n + 1100, dtype=np.int64) * 1000
        imu = ImuSamples.from_arrays(t, rng.normal(size=(t.size, 3)), rng.normal(size=(t.size, 3)))
        buf = ImuBuffer()
        buf.add(imu[:n])
        cpu = []
        for k in range(300):
            i0, i1 = n + k * 10 // 3, n + (k + 1) * 10 // 3
            c0 = time.thread_time()
            buf.add(imu[i0:i1])
            buf.pieces(int(t[i0 - 2]), int(t[i1 - 1]) - 300)
            cpu.append((time.thread_time() - c0) * 1e3)
        out.update(latency_summary(cpu, f"step_cpu_{label}_"))
    return out


BENCHMARKS = {"backends": bench_backends, "polarity_sim": bench_polarity_sim, "ego_motion_dynamic": bench_ego_motion_dynamic,
              "ablation": bench_ablation, "ablation_texture": bench_ablation_texture, "ablation_seeds": bench_ablation_seeds, "ablation_long": bench_ablation_long, "realtime_300hz": bench_realtime_300hz, "snapshot_restore": bench_snapshot_restore, "imu_buffer": bench_imu_buffer,
              "registration_wander": bench_registration_wander, "aligned_field": bench_aligned_field,
              "polarity_ceiling": bench_polarity_ceiling, "refinement_cost": bench_refinement_cost,
              "crowding_cost": bench_crowding_cost, "regimes": bench_fusion_regimes, "full_filter_cost": bench_full_filter_cost}
