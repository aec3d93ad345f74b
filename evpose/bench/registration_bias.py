"""Diagnostic benchmark: how far registration lands from ground truth when it starts there.

Every ``every``-th update time of the simulated landing, the front end has seen
the events so far; registration starts *at* the ground-truth pose, with the
ground-truth twist for the lag compensation and no prior, and we record where it
ends (body-frame error, rotation then translation) and the error's Mahalanobis
distance under the reported covariance (NEES; 6 on average if the covariance is
right). Two maps: the simulator's true edges sampled every 5 mm (a perfect map)
and the map ``build_contour_map`` makes from the raw cloud. A mean error far
from zero with a perfect map means the residual model is biased; a large NEES
means the covariance a filter would fuse is overconfident.

Registered in :mod:`evpose.bench.tracking` as ``registration_bias_346x260``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

EARLY_S = 0.4
"""Updates before this time (after the start) are summarised apart: the camera then moves along one image axis only
and the 6-DoF registration is worst conditioned."""


def true_edge_points(segments: np.ndarray, step_m: float = 0.005) -> np.ndarray:
    """(N, 3) points every ``step_m`` along (M, 2, 3) segments, both ends included."""
    out = []
    for a, b in np.asarray(segments, dtype=np.float64):
        n = max(int(np.linalg.norm(b - a) / step_m), 1)
        out.append(a + (b - a) * (np.arange(n + 1) / n)[:, None])
    return np.concatenate(out) if out else np.zeros((0, 3))


def _errors_from_ground_truth(recording, contour_map, config, every: int = 10, dt_us: int = 5000):
    """(times s, errors (K, 6), NEES (K,)) of registrations started at ground truth."""
    import gtsam

    from evpose.tracker.registration import register_to_map, subsample_indices
    from evpose.tracker.tracker import Tracker

    cfg = config
    tracker = Tracker(cfg, contour_map, recording.calibration)
    gt, ev = recording.ground_truth, recording.events
    t0 = int(ev.t[0]) + int(round(cfg.warmup_ms * 1e3))
    i1 = int(np.searchsorted(ev.t, t0))
    tracker.feed(ev[:i1])
    times, errs, nees = [], [], []
    reg_cfg = cfg.registration
    for k in range(1, 10**9):
        t = t0 + k * dt_us
        if t > int(ev.t[-1]) or t + dt_us > int(gt.t[-1]):
            break
        j = int(np.searchsorted(ev.t, t))
        tracker.feed(ev[i1:j])
        i1 = j
        if k % every:
            continue
        T_gt = gt.interpolate(np.array([t])).matrix(0)
        visible = tracker.visible_map.visible(T_gt, cfg.visible_map)
        pts = np.ascontiguousarray(tracker._points[visible[subsample_indices(visible.size, reg_cfg.max_points)]])
        tracker.distance_field.compute(tracker.time_surface, t, (0,), tracker._field_box(pts, T_gt), False)  # registration derives the curvature itself
        T_prev = gt.interpolate(np.array([t - dt_us])).matrix(0)
        twist = gtsam.Pose3.Logmap(gtsam.Pose3(T_prev).between(gtsam.Pose3(T_gt))) / (dt_us * 1e-6)
        res = register_to_map(tracker.distance_field, pts, T_gt, tracker.K, reg_cfg, twist_per_s=twist, prior_information=np.zeros((6, 6)))
        e = np.asarray(gtsam.Pose3.Logmap(gtsam.Pose3(T_gt).between(gtsam.Pose3(res.T_world_cam))))
        times.append((t - t0) * 1e-6)
        errs.append(e)
        nees.append(float(e @ np.linalg.solve(res.covariance, e)) if res.covariance is not None else np.nan)
    return np.array(times), np.array(errs).reshape(-1, 6), np.array(nees)


def _summary(prefix: str, errs: np.ndarray, nees: np.ndarray) -> dict:
    if errs.shape[0] == 0:
        return {}
    out = {}
    rot = np.degrees(errs[:, :3])
    tr = errs[:, 3:] * 1e3
    for i, ax in enumerate("xyz"):
        out[f"{prefix}rot_{ax}_mean_deg"] = float(rot[:, i].mean())
        out[f"{prefix}trans_{ax}_mean_mm"] = float(tr[:, i].mean())
    out[f"{prefix}trans_rms_mm"] = float(np.sqrt((tr**2).sum(1).mean()))
    out[f"{prefix}rot_rms_deg"] = float(np.sqrt((rot**2).sum(1).mean()))
    ok = np.isfinite(nees)
    out[f"{prefix}nees_median"] = float(np.median(nees[ok])) if ok.any() else float("nan")
    return out


def registration_bias(work_dir: Path, resolution: tuple[int, int], seconds: float, seed: int = 0) -> dict:
    """Registration-from-ground-truth errors with the true-edge map and the built map (see the module docstring)."""
    from evpose.bench.tracking import landing_case
    from evpose.core.contour_map import ContourMap
    from evpose.sim import SimulationConfig
    from evpose.sim.cache import load_or_simulate
    from evpose.tracker.config import TrackerConfig, TrackerMode

    rec, built = landing_case(work_dir, resolution, seconds, seed)
    sim = load_or_simulate(SimulationConfig(scenario="landing", seconds=seconds, resolution=resolution, seed=seed),
                           Path(work_dir) / "tracking" / "sim")
    edges = np.concatenate([sim.edges, sim.albedo_edges]) if len(sim.albedo_edges) else sim.edges
    out: dict = {"resolution": f"{resolution[0]}x{resolution[1]}", "seconds": seconds}
    for name, cmap in (("true_edges", ContourMap.from_points(true_edge_points(edges))), ("built", built)):
        times, errs, nees = _errors_from_ground_truth(rec, cmap, TrackerConfig(mode=TrackerMode.STPE))
        early = times < EARLY_S
        out[f"{name}_registrations"] = int(times.size)
        out.update(_summary(f"{name}_early_", errs[early], nees[early]))
        out.update(_summary(f"{name}_late_", errs[~early], nees[~early]))
    out["load_average_1min"] = os.getloadavg()[0]
    return out
