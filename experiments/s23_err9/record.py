"""In-situ revisit matches' errors against need9's model: record.py SEEDS -> /tmp/s23/err9/seedN.json (session 23, err9).
Runs landing seeds with render9's 2-D revisit search on (9a820a3 cherry-picked; cfg.search.revisit_patch_px = 31, radius
12 px, NCC 0.8) and logs every accepted match: keyframe id / time, point id, the match, the point's truth pixel (render9 /
need9: triangulated at the true poses of its earlier observations, projected at the keyframe's true pose), the projection
by the keyframe's SLAM pose (the search's centre), the warped 31 px template's edge normal (edge9's structure tensor,
Gaussian 3 px), and whether the point is one need9's oracle draws from (all observations before 1.6 s, consistent within
3 px of the triangulated truth)."""
import json, sys
import cv2, numpy as np
sys.path.insert(0, "/tmp/s22/lead"); sys.path.insert(0, "/tmp/s22/render9")
from simcache import load
import evpose.slam.system as sysmod
from evpose.slam import SlamConfig, run_slam
from evpose.eval.slam_metrics import atlas_metrics
from evpose.core.trajectory import invert_pose
from evpose.slam.geometry import project
from evpose.slam.revisit_search import warp_template
from oracle import tri
cv2.setNumThreads(1)


def edge_normal(tpl, sigma=3.0):
    g = tpl.astype(np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3); gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)
    c = g.shape[0] // 2
    yy, xx = np.mgrid[0:g.shape[0], 0:g.shape[1]]
    w = np.exp(-((xx - c) ** 2 + (yy - c) ** 2) / (2.0 * sigma ** 2))
    S = np.array([[np.sum(w * gx * gx), np.sum(w * gx * gy)], [np.sum(w * gx * gy), np.sum(w * gy * gy)]], np.float64)
    ev, V = np.linalg.eigh(S)
    return V[:, 1], float(1 - ev[0] / max(ev[1], 1e-12))


G = {}
_orig = sysmod.revisit_points


def wrap(m, kf, img8, K, window, cfg):
    before = {pid: dict(p.obs) for pid, p in m.points.items()}
    poses = {k.id: k.T_wc for k in m.keyframes}
    times = {k.id: k.t_us for k in m.keyframes}
    T_slam = kf.T_wc.copy()
    n = _orig(m, kf, img8, K, window, cfg)
    gt, t0 = G["gt"], G["t0"]
    if len(m.keyframes) > window:
        G["kfs"].append(dict(kf=kf.id, t=(kf.t_us - t0) / 1e6, n=n))
    if n == 0:
        return n
    T_true = gt.interpolate([kf.t_us]).matrices()[0]
    for pid, p in m.points.items():
        if kf.id not in p.obs or kf.id in before.get(pid, {}):
            continue
        ids = sorted(i for i in before[pid] if i in times)
        rec = dict(kf=kf.id, t=(kf.t_us - t0) / 1e6, pid=pid, uv=p.obs[kf.id].tolist(), nobs=len(ids),
                   last_t=(times[ids[-1]] - t0) / 1e6 if ids else None)
        rec["proj"] = project(K, invert_pose(T_slam), p.xyz[None])[0][0].tolist()
        if p.context is not None and p.context_kf in poses:
            tpl = warp_template(p.context, K, poses[p.context_kf], T_slam, p.xyz, np.array(rec["proj"]), 31)
            nrm, coh = edge_normal(tpl)
            rec["normal"], rec["coh"] = nrm.tolist(), coh
        if len(ids) >= 2:
            Tg = gt.interpolate([times[i] for i in ids]).matrices()
            X = tri(K, [invert_pose(T) for T in Tg], [before[pid][i] for i in ids])
            rec["truth"] = project(K, invert_pose(T_true), X[None])[0][0].tolist()
            rec["cons"] = float(max(np.linalg.norm(project(K, invert_pose(T), X[None])[0][0] - before[pid][i])
                                    for T, i in zip(Tg, ids)))
        G["log"].append(rec)
    return n


sysmod.revisit_points = wrap
for s in sys.argv[1].split(","):
    rec = load("landing", int(s))
    G.update(gt=rec.ground_truth, t0=int(rec.events.t[0]), log=[], kfs=[])
    cfg = SlamConfig(); cfg.search.revisit_patch_px = 31
    run = run_slam(rec, cfg)
    ate = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s).ate_percent
    json.dump(dict(seed=int(s), ate=ate, matches=G["log"], kfs=G["kfs"]), open(f"/tmp/s23/err9/seed{s}.json", "w"))
    print(s, f"ATE {ate:.3f}%", "matches", len(G["log"]), flush=True)
