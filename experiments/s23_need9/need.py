"""What must a post-turn revisit matcher reach? need.py NAME SEEDS Q P [WRONG [SALT]]   (session 23, need9; adapted from
/tmp/s23/edge9/oracle1d.py, 2-D mode). At each keyframe after 2.0 s, every point last observed before the local window with
all observations before 1.6 s (true position triangulated at the true poses of its observations, consistent within 3 px)
that projects into the image at the keyframe's true pose is a candidate; it is KEPT with probability Q (yield) and, if
kept, is RIGHT with probability P (precision): right = true pixel + 0.7 px Gaussian noise per axis (the oracle's draws,
so Q = P = 1 is the session-23 oracle bit for bit); wrong = true pixel displaced by a random 3-10 px (either sign)
  WRONG=edge (default): ALONG the edge of the point's template (the structure tensor's minor eigenvector of the 31 px
        context warped through the keyframe's estimated pose, revisit_search.edge_normal; random direction if the
        warped template is flat), i.e. the realistic failure mode of the matchers tried (aperture problem);
  WRONG=any: in a uniformly random direction;
  WRONG=pred: instead at the point's projection by the keyframe's SLAM pose (its map position; a median 3-8 px off the
        truth), i.e. a match that confirms the drift;
plus the same 0.7 px noise. Kept observations enter the local BA as ordinary 2-D keyframe observations (p.obs).
Keep/wrong/offset draws come from their own generator seeded (seed, keyframe id, point id[, SALT]), independent of the
noise; SALT > 0 gives another draw of them (to see how much of a figure is the chaos after the turn).
Writes /tmp/s23/need9/NAME.json in exp.py's format plus per-seed counts (candidates, kept, wrong, post-2 s keyframes).
PYTHONPATH at /work/s23-need9 (main 25e4e4b + cherry-picked revisit_search / MapPoint.edge_obs of s23-edge9)."""
import json, sys
import cv2, numpy as np
sys.path.insert(0, "/tmp/s22/lead"); sys.path.insert(0, "/tmp/s22/render9")
from simcache import load
import evpose.slam.system as sysmod
from evpose.slam import SlamConfig, run_slam
from evpose.eval.slam_metrics import atlas_metrics
from evpose.core.trajectory import invert_pose
from evpose.slam.geometry import project
from evpose.slam.revisit_search import edge_normal, warp_template
from oracle import tri
cv2.setNumThreads(1)
name, seeds, Q, P = sys.argv[1:5]
Q, P = float(Q), float(P)
wrong_mode = sys.argv[5] if len(sys.argv) > 5 else "edge"
salt = int(sys.argv[6]) if len(sys.argv) > 6 else 0  # another draw of the keep / wrong decisions (0: the first)
noise = 0.7
G = {}


def need_revisit(m, kf, img8, K, window, cfg):
    gt, t0 = G["gt"], G["t0"]
    if len(m.keyframes) <= window or kf.t_us - t0 < 2.0e6:
        return 0
    G["kfs"] += 1
    first = m.keyframes[-window:][0].id
    times = {k.id: k.t_us for k in m.keyframes}
    poses = {k.id: k.T_wc for k in m.keyframes}
    T_true = gt.interpolate([kf.t_us]).matrices()[0]
    rng = np.random.default_rng(1000 * G["seed"] + kf.id)
    h, w = img8.shape
    n_added = 0
    for pid, p in sorted(m.points.items()):
        if not p.obs or max(p.obs) >= first or kf.id in p.obs or p.context is None or p.context_kf not in poses:
            continue
        ts = sorted(times[i] for i in p.obs if i in times)
        if len(ts) < 2 or ts[-1] - t0 >= 1.6e6:
            continue
        ids = sorted(i for i in p.obs if i in times)
        Tg = gt.interpolate([times[i] for i in ids]).matrices()
        X = tri(K, [invert_pose(T) for T in Tg], [p.obs[i] for i in ids])
        if max(np.linalg.norm(project(K, invert_pose(T), X[None])[0][0] - p.obs[i]) for T, i in zip(Tg, ids)) >= 3.0:
            continue
        q, z = project(K, invert_pose(T_true), X[None])
        q = q[0]
        if z[0] <= 0 or not (16 <= q[0] < w - 17 and 16 <= q[1] < h - 17):
            continue
        uv = q + rng.normal(0, noise, 2)  # the oracle's draw, whatever is kept
        G["cand"] += 1
        r2 = np.random.default_rng([G["seed"], kf.id, pid] + ([salt] if salt else []))
        u_keep, u_wrong, u_sign, u_mag, u_ang = r2.random(5)
        if u_keep >= Q:
            continue
        if u_wrong >= P and wrong_mode == "pred":  # the projection by the keyframe's SLAM pose, where a search starts
            uv = uv - q + project(K, invert_pose(kf.T_wc), p.xyz[None])[0][0]
            G["wrong"] += 1
        elif u_wrong >= P:
            d = None
            if wrong_mode == "edge":
                proj = project(K, invert_pose(kf.T_wc), p.xyz[None])[0][0]
                tpl = warp_template(p.context, K, poses[p.context_kf], kf.T_wc, p.xyz, proj, 31)
                if float(tpl.std()) >= cfg.min_texture:
                    n = edge_normal(tpl)
                    d = np.array([-n[1], n[0]])
                else:
                    G["flat"] += 1
            if d is None:
                d = np.array([np.cos(2 * np.pi * u_ang), np.sin(2 * np.pi * u_ang)])
            uv = uv + (1.0 if u_sign < 0.5 else -1.0) * (3.0 + 7.0 * u_mag) * d
            G["wrong"] += 1
        p.obs[kf.id] = uv
        n_added += 1
    G["n"] += n_added
    return n_added


sysmod.revisit_points = need_revisit
seed_list = []
for s in seeds.split(","):
    a, _, b = s.partition("-"); seed_list += list(range(int(a), int(b or a) + 1))
rows = {}
for seed in seed_list:
    rec = load("landing", seed)
    G.update(gt=rec.ground_truth, t0=int(rec.events.t[0]), seed=seed, n=0, cand=0, wrong=0, flat=0, kfs=0)
    cfg = SlamConfig(); cfg.search.revisit_patch_px = 31; cfg.search.revisit_along_sigma_px = 10.0
    run = run_slam(rec, cfg)
    ate = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s).ate_percent
    rows[seed] = dict(ate=ate, added=G["n"], candidates=G["cand"], wrong=G["wrong"], flat=G["flat"], keyframes=G["kfs"])
    print(name, seed, f"{ate:.3f}%", "kept", G["n"], "of", G["cand"], "wrong", G["wrong"], "flat", G["flat"], "kfs", G["kfs"],
          flush=True)
ates = [r["ate"] for r in rows.values()]
tot = {k: int(sum(r[k] for r in rows.values())) for k in ("added", "candidates", "wrong", "flat", "keyframes")}
summary = dict(name=name, Q=Q, P=P, wrong_mode=wrong_mode, salt=salt, noise=noise, seeds=seed_list, mean=float(np.mean(ates)),
               median=float(np.median(ates)), within2=int(sum(a <= 2.0 for a in ates)), worst=float(max(ates)), totals=tot,
               rows=rows)
open(f"/tmp/s23/need9/{name}.json", "w").write(json.dumps(summary, indent=1))
print(name, "mean", f"{summary['mean']:.3f}", "within2", summary["within2"], "of", len(ates), tot)
