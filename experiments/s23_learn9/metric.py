"""Learnt Mahalanobis metric on normalised patches (KISSME: M = inv(C_same) - inv(C_diff) on PCA-reduced difference
vectors of the warped 31 px template and the target patch): metric.py TRAIN.pkl TEST.pkl [pca_dims]
Patches blurred (sigma 1), sampled every 2nd pixel (16 x 16), zero mean, unit norm (identity M = NCC ranking).
Prints the truth's rank in the window and the precision-yield curve of the metric's peak by its margin, and of the
peak re-verified by learn.py's logistic verifier features."""
import sys
import cv2, numpy as np
sys.argv += ["tmpl"] if len(sys.argv) < 4 else []
DIMS = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[3].isdigit() else 60
sys.argv = sys.argv[:3] + ["tmpl"]
import learn
from learn import load, truth, xx, yy, R, peak, logreg, curve
from numpy.lib.stride_tricks import sliding_window_view


def norm(P):
    P = P - P.mean(-1, keepdims=True)
    return P / (np.linalg.norm(P, axis=-1, keepdims=True) + 1e-6)


def vecs(p):
    t = cv2.GaussianBlur(p["tpl"].astype(np.float32), (0, 0), 1.0)[::2, ::2].ravel()
    g = cv2.GaussianBlur(p["reg"].astype(np.float32), (0, 0), 1.0)
    Q = sliding_window_view(g, (31, 31))[:, :, ::2, ::2].reshape((2 * R + 1) ** 2, -1)
    return norm(t[None])[0], norm(Q)


def main():
    _, tr = load(sys.argv[1]); _, te = load(sys.argv[2])
    rng = np.random.default_rng(0)
    S, D = [], []
    for p in tr:
        d = np.hypot(xx + p["off"][0] - truth(p)[0], yy + p["off"][1] - truth(p)[1]).ravel()
        if d.min() > 1.0:
            continue
        t, Q = vecs(p)
        valid = (p["F"][0].ravel() > -1) & (d > 2.0)
        S.append(t - Q[np.argmin(d)])
        far = np.flatnonzero(valid)
        hard = far[np.argsort(-(Q[far] @ t))[:10]]
        for j in np.r_[hard, rng.choice(far, 10, replace=False)]:
            D.append(t - Q[j])
    S, D = np.array(S), np.array(D)
    allv = np.r_[S, D]
    mu = allv.mean(0)
    U, sv, Vt = np.linalg.svd(allv - mu, full_matrices=False)
    Pm = Vt[:DIMS].T
    Cs = np.cov((S @ Pm).T) + 1e-4 * np.eye(DIMS); Cd = np.cov((D @ Pm).T) + 1e-4 * np.eye(DIMS)
    M = np.linalg.inv(Cs) - np.linalg.inv(Cd)
    print(f"train: {len(S)} positives, {len(D)} negatives, PCA {DIMS}", flush=True)

    def score_map(p):
        t, Q = vecs(p)
        Z = (t[None] - Q) @ Pm
        s = -np.einsum("ij,jk,ik->i", Z, M, Z)
        s = s.reshape(2 * R + 1, 2 * R + 1)
        s[p["F"][0] <= -1] = -1e9
        return s

    nkf = len({(p["seed"], p["kf"]) for p in te})
    ranks, X, Y = [], [], []
    for p in te:
        s = score_map(p)
        d = np.hypot(xx + p["off"][0] - truth(p)[0], yy + p["off"][1] - truth(p)[1])
        if d.min() <= 1.0:
            far = (d > 2.0) & (p["F"][0] > -1)
            ranks.append(int((s[far] > s[d <= 1.0].max()).sum()))
        # standardise scores so the verifier features are comparable across pairs
        v = s[s > -1e8]
        sz = (s - v.mean()) / (v.std() + 1e-9)
        sz[s <= -1e8] = -50
        uv, f = peak(sz, p)
        if uv is None:
            continue
        X.append(f); Y.append(np.linalg.norm(uv - truth(p)) <= 2.0)
    r = np.array(ranks)
    print(f"metric: truth rank (positions beyond 2 px scoring higher) median {np.median(r):.0f}, best {np.mean(r == 0) * 100:.0f}% top5 {np.mean(r < 5) * 100:.0f}% top20 {np.mean(r < 20) * 100:.0f}% of {len(r)} pairs")
    X, Y = np.array(X), np.array(Y)
    print(f"metric peaks {len(Y)}, right {int(Y.sum())} ({Y.sum() / nkf:.2f}/kf, {100 * Y.mean():.0f}%)")
    curve(X[:, 0], Y, nkf, "  metric peak score")
    curve(X[:, 2], Y, nkf, "  metric margin")


if __name__ == "__main__":
    main()
