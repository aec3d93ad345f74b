"""Best-of-five selection by an online signal: summary.py DIR (reads sig_[ho_]NAME.json written by sig.py)."""
import json, sys
import numpy as np
from scipy.stats import spearmanr

d = sys.argv[1] if len(sys.argv) > 1 else "."
names = ["def", "h19", "h21", "r24", "r26"]
for pre, lab in [("", "0-23"), ("ho_", "24-47")]:
    D = {n: json.load(open(f"{d}/sig_{pre}{n}.json"))["rows"] for n in names}
    seeds = sorted(D["def"], key=int); N = len(seeds)
    A = np.array([[D[n][s]["ate"] for n in names] for s in seeds])
    print(lab, "means", A.mean(0).round(3), "all %.3f within2 %d/%d" % (A.mean(), (A <= 2).sum(), A.size),
          "best-of-5 oracle %.3f (%d)" % (A.min(1).mean(), (A.min(1) <= 2).sum()))
    for k in ["rough", "mt", "inl"]:
        X = np.array([[D[n][s][k] for n in names] for s in seeds])
        rho = np.nanmean([spearmanr(X[i], A[i]).correlation for i in range(N)])
        pick = np.argmin(X, 1) if k == "rough" else np.argmax(X, 1)
        sel = A[np.arange(N), pick]
        print("  %s within-seed rho %.2f, pooled %.2f, picked %.3f, within2 %d" % (
            k, rho, spearmanr(X.ravel(), A.ravel()).correlation, sel.mean(), (sel <= 2).sum()))
