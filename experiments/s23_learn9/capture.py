"""Capture per-keyframe MCIs (unsigned float, 8-bit, signed polarity twin), SLAM poses and map snapshots: capture.py SEEDS
-> /tmp/s23/learn9/cap/landing_seedN.pkl. Run with PYTHONPATH at the s22-render9 checkout."""
import pickle, sys
import cv2, numpy as np
sys.path.insert(0, "/tmp/s22/lead")
from simcache import load
import evpose.slam.mci as mcimod
from evpose.slam import SlamConfig, run_slam
from evpose.slam.system import EventSlam
from evpose.eval.slam_metrics import atlas_metrics
cv2.setNumThreads(1)

_orig_ei = mcimod.event_image
CUR = {"rw": None, "signed": {}}

def ei_wrap(x, y, p, width, height, sigma=1.0, slice_idx=None, homographies=None):
    img = _orig_ei(x, y, p, width, height, sigma, slice_idx, homographies)
    rw = CUR["rw"]
    if p is None and rw is not None and len(rw.p) == len(x):
        CUR["signed"][id(img)] = _orig_ei(x, y, rw.p.astype(np.float64), width, height, sigma, slice_idx, homographies)
    return img
mcimod.event_image = ei_wrap

_orig_gen = mcimod.MciGenerator.generate
def gen_wrap(self, rw, prior=None):
    CUR["rw"], CUR["signed"] = rw, {}
    res = _orig_gen(self, rw, prior)
    CUR["rw"] = None
    return res
mcimod.MciGenerator.generate = gen_wrap

KFS = []
_orig_tm = EventSlam._track_map
def tm_wrap(self, mci):
    self._cap_mci = mci
    return _orig_tm(self, mci)
EventSlam._track_map = tm_wrap

_orig_nk = EventSlam._new_keyframe
def nk_wrap(self, m, t_us, T_wc, img8=None, adjust=True):
    mci = getattr(self, "_cap_mci", None)
    T_in = T_wc.copy()
    out = _orig_nk(self, m, t_us, T_wc, img8, adjust)
    kf = m.keyframes[-1]
    signed = CUR["signed"].get(id(mci.image)) if mci is not None else None
    KFS.append(dict(map=m.id, kf=kf.id, t=int(t_us), T_pnp=T_in, T_ba=kf.T_wc.copy(), img8=img8.copy() if img8 is not None else None,
                    img=mci.image.copy() if mci is not None else None, signed=None if signed is None else signed.copy(),
                    hyp=mci.hypothesis.value if mci is not None else None,
                    pts={pid: (p.xyz.copy(), {k: v.copy() for k, v in p.obs.items()}) for pid, p in m.points.items()},
                    kf_times={k.id: k.t_us for k in m.keyframes}, kf_poses={k.id: k.T_wc.copy() for k in m.keyframes}))
    return out
EventSlam._new_keyframe = nk_wrap

for s in sys.argv[1].split(","):
    KFS.clear()
    rec = load("landing", int(s))
    cfg = SlamConfig()
    run = run_slam(rec, cfg)
    m = atlas_metrics(run.trajectories(), rec.ground_truth, correct_scale=True, duration_s=run.duration_s)
    print(s, f"{m.ate_percent:.3f}%", len(KFS), "keyframes", sum(k["signed"] is not None for k in KFS), "signed", flush=True)
    trajs = [(mm.id, mm.trajectory()) for mm in run.atlas.maps if mm.traj_t]
    with open(f"/tmp/s23/learn9/cap/landing_seed{s}.pkl", "wb") as f:
        pickle.dump(dict(seed=int(s), ate=m.ate_percent, kfs=KFS, K=rec.calibration.K, t0=int(rec.events.t[0]), trajs=trajs), f)
