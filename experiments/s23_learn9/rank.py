"""Rank of the true position among the search window's positions per score: rank.py TRAIN.pkl TEST.pkl."""
import sys, numpy as np
sys.argv += ["tmpl"]
import learn
from learn import *
_, tr = load(sys.argv[1]); _, te = load(sys.argv[2])
sc = clogit(clogit_data(tr, np.random.default_rng(0)))
names = ["ncc31", "ncc21", "ncc11", "blur31", "ori31", "ori15", "mag31", "ncc41", "ncc51", "signed31"]
ranks = {n: [] for n in names + ["clogit"]}
nfar = []
for p in te:
    d = np.hypot(xx + p["off"][0] - truth(p)[0], yy + p["off"][1] - truth(p)[1]).ravel()
    if d.min() > 1.0: continue
    valid = p["F"][0].ravel() > -1
    near, far = d <= 1.0, valid & (d > 2.0)
    for i, n in enumerate(names):
        s = p["F"][i].ravel(); ranks[n].append(int((s[far] > s[near].max()).sum()))
    s = sc(pos_feats(p["F"])); ranks["clogit"].append(int((s[far] > s[near].max()).sum()))
    nfar.append(int(far.sum()))
print("positions beyond 2 px per window: median", np.median(nfar))
for n, r in ranks.items():
    r = np.array(r)
    print(f"{n:>8}: pairs {len(r)} rank median {np.median(r):.0f}, best {np.mean(r == 0) * 100:.0f}% top5 {np.mean(r < 5) * 100:.0f}% top20 {np.mean(r < 20) * 100:.0f}%")
