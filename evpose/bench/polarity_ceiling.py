"""Why the polarity filter does not help ``stpe`` on the plain simulated landing: its errors and its ceiling.

Benchmark ``fusion.polarity_ceiling`` runs ``stpe+filter`` from ground truth and,
per update, compares each single-polarity point's prediction with the polarity the
SP-TS shows within 1.5 px of the point's *true* projection in the last two time-
surface constants (an oracle: it needs the ground truth). It reports:

* how many points have such an observation and how many see both polarities there
  (the events the filter could remove from a point's own patch);
* the wrong-prediction rate outside the buffer zone with the fused motion and with
  the true motion (same signs): is the motion estimate the cause?
* ATE/ARE of ``stpe``, ``stpe+filter``, and ``stpe+filter`` with oracle polarities:
  every point the observed one (``oracle_all``), or only the wrongly predicted ones
  reopened to both polarities (``oracle_reopen_wrong``): the ceiling of any better
  prediction on this scene.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def observed_polarity(surface, points, T_world_cam, K, t_us: int, radius_px: float = 1.5, recent_eta: float = 2.0):
    """Per point: sign(#pixels with a recent ON - #with a recent OFF event) within ``radius_px`` of its projection at
    ``T_world_cam``, and whether both polarities are there; int8 (N,), bool (N,)."""
    X = (np.asarray(points, np.float64) - T_world_cam[:3, 3]) @ T_world_cam[:3, :3]
    u = K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2]
    v = K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2]
    on, off = surface.last_of(1), surface.last_of(-1)
    h, w = on.shape
    recent = int(t_us) - int(recent_eta * surface.config.eta_ms * 1e3)
    n_on = np.zeros(len(X))
    n_off = np.zeros(len(X))
    r = int(np.ceil(radius_px))
    cu, cv = np.round(u).astype(np.int64), np.round(v).astype(np.int64)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            xx, yy = cu + dx, cv + dy
            ok = (xx >= 0) & (xx < w) & (yy >= 0) & (yy < h) & ((xx - u) ** 2 + (yy - v) ** 2 <= radius_px**2)
            xi, yi = np.clip(xx, 0, w - 1), np.clip(yy, 0, h - 1)
            n_on += ok & (on[yi, xi] >= recent)
            n_off += ok & (off[yi, xi] >= recent)
    return np.sign(n_on - n_off).astype(np.int8), (n_on > 0) & (n_off > 0)


def _true_motion(gt, t_us: int, half_us: int = 2000):
    """World velocity and camera-frame angular rate of the ground truth at ``t_us`` (central differences)."""
    T0, T1 = gt.interpolate(int(t_us) - half_us).matrix(0), gt.interpolate(int(t_us) + half_us).matrix(0)
    dt = 2 * half_us * 1e-6
    return (T1[:3, 3] - T0[:3, 3]) / dt, Rotation.from_matrix(T0[:3, :3].T @ T1[:3, :3]).as_rotvec() / dt


def ceiling_run(recording, contour_map, oracle: str | None = None) -> dict:
    """One ``stpe+filter`` run with the prediction scored against the observed polarity; ``oracle`` None (the filter's
    own prediction), ``"all"`` or ``"reopen_wrong"`` replaces it as described in the module docstring."""
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.fusion.polarity import MapPolaritySelector, PolarityPredictor
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    session = TrackingSession(recording, contour_map, TrackerConfig(mode=TrackerMode.STPE_FILTER))
    selector = session.tracker.polarity_selector
    surface, gt = session.tracker.time_surface, recording.ground_truth
    true_motion = PolarityPredictor(selector.predictor.config)
    n = {"points": 0, "observed": 0, "both_seen": 0, "judged": 0, "wrong": 0, "judged_true_motion": 0, "wrong_true_motion": 0}
    own = selector.__call__

    def predict(T_pred, t_us, idx):
        pol = own(T_pred, t_us, idx)
        T = gt.interpolate(int(t_us)).matrix(0)
        obs, both = observed_polarity(surface, contour_map.points[idx], T, selector.K, int(t_us))
        v, omega = _true_motion(gt, int(t_us))
        true_motion._votes = selector.predictor._votes  # the same learned signs: only the motion differs
        m = contour_map
        pol_true = true_motion.predict_full(m.points, m.edge_normal, m.brightness_sign, T, omega, v, selector.K, idx, rows=idx).polarity
        judged, judged_t = (pol != 0) & (obs != 0), (pol_true != 0) & (obs != 0)
        wrong = judged & (pol != obs)
        n["points"] += idx.size
        n["observed"] += int(np.count_nonzero(obs))
        n["both_seen"] += int(np.count_nonzero(both))
        n["judged"] += int(np.count_nonzero(judged))
        n["wrong"] += int(np.count_nonzero(wrong))
        n["judged_true_motion"] += int(np.count_nonzero(judged_t))
        n["wrong_true_motion"] += int(np.count_nonzero(judged_t & (pol_true != obs)))
        if oracle == "all":
            return obs
        if oracle == "reopen_wrong":
            return np.where(wrong, 0, pol).astype(np.int8)
        return pol

    session.tracker.polarity_selector = predict  # the tracker calls it; align/observe still go to the selector
    predict.align, predict.observe = selector.align, selector.observe
    predict.points_to_register, predict.registration_covariance = selector.points_to_register, selector.registration_covariance
    session.run()
    ev = evaluate(session.trajectory(), gt, EvalConfig(align=Alignment.NONE))
    return {"ate_rmse_mm": ev.ate["rmse"] * 1e3, "are_rmse_deg": ev.are["rmse"],
            "points_observed_share": n["observed"] / n["points"], "points_both_polarities_share": n["both_seen"] / n["points"],
            "wrong_outside_buffer_share": n["wrong"] / max(n["judged"], 1),
            "wrong_outside_buffer_true_motion_share": n["wrong_true_motion"] / max(n["judged_true_motion"], 1)}


def bench_polarity_ceiling(ctx) -> dict:
    """The polarity filter's prediction errors and oracle ceiling on the simulated landing (seed ``ctx.seed``), both
    resolutions (quick: 240x180, 1 s)."""
    from evpose.bench.fusion_tracking import ablation_run
    from evpose.bench.tracking import landing_case

    cases = (((240, 180), 1.0),) if ctx.quick else (((346, 260), 2.0), ((240, 180), 2.0))
    out: dict = {}
    for res, seconds in cases:
        rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed)
        tag = f"{res[0]}x{res[1]}_"
        stpe = ablation_run(rec, cmap, "stpe")
        out[tag + "stpe_ate_rmse_mm"], out[tag + "stpe_are_rmse_deg"] = stpe["ate_rmse_mm"], stpe["are_rmse_deg"]
        for oracle in (None, "all", "reopen_wrong"):
            run = ceiling_run(rec, cmap, oracle)
            name = "stpe+filter_" if oracle is None else f"stpe+filter_oracle_{oracle}_"
            keys = run if oracle is None else ("ate_rmse_mm", "are_rmse_deg")
            out.update({tag + name + k: run[k] for k in keys})
    return out
