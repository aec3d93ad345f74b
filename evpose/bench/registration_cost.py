"""Registration latency against the number of map points: what one ``register_to_map`` call costs besides the points.

The inputs of every 10th registration of a tracking run on the simulated moderate
landing (fields, points, predicted pose, twist, prior) are recorded, then each is
registered again with evenly strided subsets of its points (``subsample_indices``,
as the tracker subsamples). Per call: this thread's CPU time, the minimum of a few
repeats (the machine is shared; the minimum is the least disturbed run).

A least-squares fit over every call, ``t = fixed + per_linearisation * L +
per_point * M * L`` with ``L`` the linearisations (LM iterations plus one per
level) and ``M`` the points, splits the cost into the per-call part (setup, health
checks, covariance, result), the per-iteration part that does not depend on the
points (pose algebra, prior, damped solve, the compiled kernel's dispatch) and the
per-point work of the compiled kernel. Registered under ``tracking``.
"""

from __future__ import annotations

import copy
import os
import time

import numpy as np

POINT_COUNTS = (25, 50, 100, 250, 500, 1000)
"""Subset sizes registered (the tracker uses up to ``registration.max_points`` = 1000)."""


def capture_registrations(recording, contour_map, mode: str, every: int = 10, limit: int = 40) -> list[tuple]:
    """``(levels, points, args, kwargs)`` of every ``every``-th ``register_to_map`` call of a ``mode`` run (deep
    copies, at most ``limit``), recorded by wrapping the tracker's reference to it for the run."""
    from evpose.tracker import tracker as tracker_module
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    calls: list[tuple] = []
    seen = [0]
    original = tracker_module.register_to_map

    def recording_wrapper(levels, points, *args, **kwargs):
        if seen[0] % every == 0 and len(calls) < limit:
            calls.append((copy.deepcopy(levels), np.array(points), copy.deepcopy(args), copy.deepcopy(kwargs)))
        seen[0] += 1
        return original(levels, points, *args, **kwargs)

    tracker_module.register_to_map = recording_wrapper
    try:
        TrackingSession(recording, contour_map, TrackerConfig(mode=TrackerMode(mode))).run()
    finally:
        tracker_module.register_to_map = original
    return calls


PER_POINT_KWARGS = ("tangents_world", "trail_offsets_px")
"""``register_to_map`` keyword arguments with one row per map point: they follow the subset as the points do."""


def registration_cost_table(calls: list[tuple], repeats: int = 5) -> dict:
    """Latency per point count (median over the calls of the min-of-``repeats`` CPU time) and the fitted split."""
    from evpose.tracker.registration import register_to_map, subsample_indices

    out: dict = {}
    rows = []  # (linearisations, points, microseconds)
    for m in POINT_COUNTS:
        lat, iters = [], []
        for levels, points, args, kwargs in calls:
            idx = subsample_indices(points.shape[0], m)
            a = list(args)
            if len(a) > 3 and a[3] is not None:  # per-point polarity follows the subset
                a[3] = np.asarray(a[3])[idx]
            pts = points[idx]
            kw = {k: (np.asarray(v)[idx] if k in PER_POINT_KWARGS and v is not None else v) for k, v in kwargs.items()}
            res = register_to_map(levels, pts, *a, **kw)  # first call: caches warm, kernels loaded
            best = np.inf
            for _ in range(repeats):
                c0 = time.thread_time()
                register_to_map(levels, pts, *a, **kw)
                best = min(best, time.thread_time() - c0)
            us = best * 1e6
            lat.append(us)
            iters.append(res.iterations)
            rows.append((res.iterations + len(levels), pts.shape[0], us))
        out[f"points_{m}_median_us"] = float(np.median(lat))
        out[f"points_{m}_iterations_mean"] = float(np.mean(iters))
    r = np.asarray(rows, np.float64)
    fixed, per_lin, per_point = split_cost(r[:, 0], r[:, 1], r[:, 2])
    out["fit_fixed_per_call_us"] = fixed
    out["fit_per_linearisation_us"] = per_lin
    out["fit_per_point_linearisation_ns"] = per_point * 1e3
    # What a typical call at the tracker's point count spends outside the per-point work.
    full = r[r[:, 1] == r[:, 1].max()]
    typical_l = float(np.median(full[:, 0]))
    out["typical_linearisations"] = typical_l
    out["typical_fixed_us"] = fixed + per_lin * typical_l
    out["typical_fixed_share"] = out["typical_fixed_us"] / out[f"points_{POINT_COUNTS[-1]}_median_us"]
    return out


def split_cost(linearisations: np.ndarray, points: np.ndarray, us: np.ndarray) -> tuple[float, float, float]:
    """Least-squares ``(fixed, per_linearisation, per_point_linearisation)`` of ``us = fixed + a L + b M L``."""
    L = np.asarray(linearisations, np.float64)
    A = np.stack([np.ones(L.size), L, L * np.asarray(points, np.float64)], axis=1)
    coef, *_ = np.linalg.lstsq(A, np.asarray(us, np.float64), rcond=None)
    return float(coef[0]), float(coef[1]), float(coef[2])


def bench_registration_cost(ctx) -> dict:
    """``register_to_map`` latency against the point count in ``full`` and ``stpe`` on the simulated landing
    (346x260, 2 s; 240x180, 1 s quick), and the fitted per-call / per-linearisation / per-point split."""
    from evpose.bench.tracking import landing_case

    res, seconds = ((240, 180), 1.0) if ctx.quick else ((346, 260), 2.0)
    rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "seconds": seconds}
    for mode in ("full", "stpe"):
        calls = capture_registrations(rec, cmap, mode, limit=20 if ctx.quick else 40)
        out[f"{mode}_calls"] = len(calls)
        out.update({f"{mode}_{k}": v for k, v in registration_cost_table(calls, 3 if ctx.quick else 5).items()})
    out["load_average_1min"] = os.getloadavg()[0]
    return out
