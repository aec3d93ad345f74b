"""Internal signals vs ATE across neutral perturbations: sig.py NAME 'cfg stmts' SEEDS -> /tmp/s23/lead/sig_NAME.json.
Per seed: scale-aligned ATE and online signals of the run after 2.0 s (PnP inliers, map tracks), the estimated
trajectory's roughness and the final map's planarity."""
import json, sys, time
from pathlib import Path
import cv2, numpy as np
sys.path.insert(0, "/tmp/s22/lead")
from simcache import load
from evpose.eval.slam_metrics import atlas_metrics
from evpose.slam import SlamConfig, run_slam

name, stmts, seeds = sys.argv[1:4]
cv2.setNumThreads(1)
a, _, b = seeds.partition("-"); seed_list = list(range(int(a), int(b or a) + 1))
rows = {}
for seed in seed_list:
    rec = load("landing", seed)
    cfg = SlamConfig(); exec(stmts, {"cfg": cfg, "np": np})
    run = run_slam(rec, cfg)
    m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s)
    t0 = int(run.results[0].t_us) if run.results else 0
    late = [r for r in run.results if r.t_us - t0 >= 2.0e6 and r.mcis > 0]
    inl = [r.counts.get("inliers", -1) for r in late if r.counts.get("inliers", -1) >= 0]
    mt = [r.counts.get("map_tracks", -1) for r in late if r.counts.get("map_tracks", -1) >= 0]
    # roughness: RMS second difference of the main map's positions, over its path length
    trajs = run.trajectories()
    tr = max(trajs.values() if isinstance(trajs, dict) else trajs, key=lambda t: len(t.t))
    P = tr.position
    L = float(np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1))) or 1.0
    rough = float(np.sqrt(np.mean(np.sum(np.diff(P, 2, axis=0) ** 2, axis=1)))) / L
    # planarity of the last map: share of points within 3 % of the median depth scale from the best plane (SVD)
    pts = next((r.map_points for r in reversed(run.results) if r.map_points is not None and len(r.map_points) > 10), None)
    plan = np.nan
    if pts is not None:
        c = np.median(pts, 0); u, s, vt = np.linalg.svd(pts - c, full_matrices=False)
        d = np.abs((pts - c) @ vt[2]); scale = np.median(np.linalg.norm(pts - c, axis=1))
        plan = float(np.mean(d < 0.03 * scale))
    rows[seed] = dict(ate=m.ate_percent, inl=float(np.mean(inl)) if inl else np.nan, inl_min=float(np.percentile(inl, 10)) if inl else np.nan,
                      mt=float(np.mean(mt)) if mt else np.nan, rough=rough, plan=plan, maps=len(m.maps))
    print(name, seed, {k: round(v, 4) for k, v in rows[seed].items()}, flush=True)
Path(f"/tmp/s23/lead/sig_{name}.json").write_text(json.dumps(dict(name=name, stmts=stmts, rows=rows), indent=1))
