"""Learnt matcher for post-turn revisits: learn.py TRAIN.pkl TEST.pkl [truth=tmpl|point]
Stage A, a score per search position from feats.py's score maps, three ways: 'learnt A' a logistic regression
(positives within 1 px of the truth, negatives beyond 2 px: the 10 highest-NCC ones, the hard ones along the edge, and
20 random); 'clogit A' a conditional logit (softmax over the window's positions, mass on the positives); 'ncc31 A'
plain NCC of the warped 31 px template. Stage B: verifier of the stage-A peak (right = within 2 px) from the peak's
scores, its uniqueness and the elongation of its ridge: logistic regression, or boosted decision stumps. Temporal:
keep a peak whose offset from the projection agrees with the same point's peak at a neighbouring keyframe.
Prints precision-yield curves (right / wrong per keyframe) on the test pairs against render9's NCC search."""
import pickle, sys
import numpy as np

R = 12
TRUTH = sys.argv[3] if len(sys.argv) > 3 else "tmpl"
yy, xx = np.mgrid[-R:R + 1, -R:R + 1]


def load(fn):
    d = pickle.load(open(fn, "rb"))
    return d["names"], d["pairs"]


def truth(p):
    return p["uv_tmpl"] if TRUTH == "tmpl" else p["uv_true"]


def pos_feats(F):
    """Per-position feature vectors (n_pos x k): the maps, their squares for the NCCs, and a pairwise product."""
    n31, n21, n11, b31, o31, o15, m31, n41, n51, sg31 = F[:10]
    dist = F[-1]
    X = [n31, n21, n11, b31, o31, o15, m31, n41, n51, sg31, np.abs(sg31), dist, dist ** 2, n31 ** 2, o31 ** 2, n11 ** 2, n31 * o31, n11 * o15] + list(F[10:28])
    return np.stack([x.ravel() for x in X], 1)


def logreg(X, y, lam=1e-2, w=None, it=50):
    """L2-regularised logistic regression by Newton's method (standardised features, intercept unpenalised)."""
    mu, sd = X.mean(0), X.std(0) + 1e-9
    Z = np.c_[np.ones(len(X)), (X - mu) / sd]
    sw = np.ones(len(X)) if w is None else w
    b = np.zeros(Z.shape[1])
    reg = lam * np.eye(Z.shape[1]); reg[0, 0] = 0
    for _ in range(it):
        pr = 1 / (1 + np.exp(-Z @ b))
        g = Z.T @ (sw * (pr - y)) + reg @ b
        H = (Z * (sw * pr * (1 - pr))[:, None]).T @ Z + reg
        step = np.linalg.solve(H, g)
        b -= step
        if np.abs(step).max() < 1e-8:
            break
    return lambda X: np.c_[np.ones(len(X)), (X - mu) / sd] @ b


def stage_a_data(pairs, rng):
    Xs, ys = [], []
    for p in pairs:
        d = np.hypot(xx + p["off"][0] - truth(p)[0], yy + p["off"][1] - truth(p)[1]).ravel()
        pos = np.flatnonzero(d <= 1.0)
        if not len(pos):
            continue
        X = pos_feats(p["F"])
        neg = np.flatnonzero((d > 2.0) & (p["F"][0].ravel() > -1))
        hard = neg[np.argsort(-p["F"][0].ravel()[neg])[:10]]
        rnd = rng.choice(neg, size=min(20, len(neg)), replace=False)
        sel = np.r_[pos, hard, rnd]
        Xs.append(X[sel]); ys.append(np.r_[np.ones(len(pos)), np.zeros(len(sel) - len(pos))])
    return np.concatenate(Xs), np.concatenate(ys)


def clogit_data(pairs, rng, top=150, nrand=50):
    """Per pair the positions compared in the softmax: the positives (within 1 px), the top NCC31 ones and random ones."""
    out = []
    for p in pairs:
        d = np.hypot(xx + p["off"][0] - truth(p)[0], yy + p["off"][1] - truth(p)[1]).ravel()
        pos = np.flatnonzero(d <= 1.0)
        if not len(pos):
            continue
        n = p["F"][0].ravel()
        valid = np.flatnonzero((n > -1) & (d > 1.0))
        hard = valid[np.argsort(-n[valid])[:top]]
        rest = np.setdiff1d(valid, hard)
        rnd = rng.choice(rest, size=min(nrand, len(rest)), replace=False) if len(rest) else rest
        sel = np.r_[pos, hard, rnd]
        out.append((pos_feats(p["F"])[sel].astype(np.float64), len(pos)))
    return out


def clogit(groups, lam=1e-2):
    """Conditional logit: per pair, softmax over its positions, maximise the probability mass on the positives."""
    from scipy.optimize import minimize
    allX = np.concatenate([g for g, _ in groups])
    mu, sd = allX.mean(0), allX.std(0) + 1e-9
    Zs = [((g - mu) / sd, k) for g, k in groups]
    def f(b):
        L = 0.5 * lam * b @ b * len(Zs); G = lam * b * len(Zs)
        for Z, k in Zs:
            s = Z @ b; m = s.max(); e = np.exp(s - m)
            ep = e[:k]
            L -= np.log(ep.sum()) - np.log(e.sum())
            G -= (ep @ Z[:k]) / ep.sum() - (e @ Z) / e.sum()
        return L, G
    r = minimize(f, np.zeros(allX.shape[1]), jac=True, method="L-BFGS-B", options=dict(maxiter=300))
    b = r.x
    print("  clogit weights", np.round(b, 2), flush=True)
    return lambda X: ((X - mu) / sd) @ b


def boost(X, y, rounds=200, nu=0.1, nq=16):
    """Gradient-boosted decision stumps on the logistic loss (deterministic): a non-linear verifier."""
    thr = [np.unique(np.quantile(X[:, j], np.linspace(0.05, 0.95, nq))) for j in range(X.shape[1])]
    F = np.full(len(y), np.log((y.mean() + 1e-9) / (1 - y.mean() + 1e-9)))
    base = F[0]
    stumps = []
    for _ in range(rounds):
        pr = 1 / (1 + np.exp(-F)); g = y - pr; h = pr * (1 - pr) + 1e-9
        best = None
        for j in range(X.shape[1]):
            for t in thr[j]:
                m = X[:, j] <= t
                gl, hl, gr, hr = g[m].sum(), h[m].sum(), g[~m].sum(), h[~m].sum()
                gain = gl * gl / (hl + 1.0) + gr * gr / (hr + 1.0)
                if best is None or gain > best[0]:
                    best = (gain, j, t, gl / (hl + 1.0), gr / (hr + 1.0))
        _, j, t, vl, vr = best
        stumps.append((j, t, nu * vl, nu * vr))
        F += np.where(X[:, j] <= t, nu * vl, nu * vr)
    return lambda Z: base + sum(np.where(Z[:, j] <= t, a, b) for j, t, a, b in stumps)


def parab(S, iy, ix, axis):
    if axis == 1:
        a, b, c = S[iy, ix - 1], S[iy, ix], S[iy, ix + 1]
    else:
        a, b, c = S[iy - 1, ix], S[iy, ix], S[iy + 1, ix]
    den = a - 2 * b + c
    return 0.0 if den >= 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))


def peak(S, p, delta=1.0):
    """Stage-A peak of score map S: (uv, verifier features) or (None, None) on the border."""
    iy, ix = np.unravel_index(int(np.argmax(S)), S.shape)
    if not (0 < iy < S.shape[0] - 1 and 0 < ix < S.shape[1] - 1):
        return None, None
    s1 = S[iy, ix]
    away = S.copy(); away[max(iy - 2, 0):iy + 3, max(ix - 2, 0):ix + 3] = -np.inf
    s2 = away.max()
    near = np.argwhere(S >= s1 - delta)
    c = np.cov(near.T) if len(near) > 2 else np.zeros((2, 2))
    ev = np.sqrt(np.maximum(np.linalg.eigvalsh(c), 0))
    F = p["F"]
    uv = np.array([p["off"][0] + ix - R + parab(S, iy, ix, 1), p["off"][1] + iy - R + parab(S, iy, ix, 0)])
    f = [s1, s2, s1 - s2, len(near), ev[1], ev[0], F[0, iy, ix], F[2, iy, ix], F[4, iy, ix], F[5, iy, ix], F[0].max(),
         F[-1, iy, ix], p["coh"], p["tstd"], (F[0] >= F[0, iy, ix] - 0.05).sum(), F[7, iy, ix], F[8, iy, ix], F[9, iy, ix], np.sort(F[10:19, iy, ix])[2], np.sort(F[19:28, iy, ix])[2],
         p["auto_max2"], p["auto_cnt"]]
    return uv, np.array(f, float)


def stage_b(pairs, scorer):
    U, X, Y, K = [], [], [], []
    for p in pairs:
        S = scorer(pos_feats(p["F"])).reshape(2 * R + 1, 2 * R + 1)
        S[p["F"][0] <= -1] = -50
        uv, f = peak(S, p)
        if uv is None:
            continue
        U.append(uv); X.append(f); Y.append(np.linalg.norm(uv - truth(p)) <= 2.0); K.append((p["seed"], p["kf"]))
    return np.array(U), np.array(X), np.array(Y, float), K


def curve(score, right, nkf, label, qs=(0.5, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95, 0.96, 0.97, 0.98, 0.99)):
    order = np.argsort(-score)
    line = [label]
    for q in qs:
        th = np.quantile(score, q)
        sel = score >= th
        r, w = int(right[sel].sum()), int((~right[sel]).sum())
        line.append(f"top{100 - q * 100:.0f}%: {r / nkf:.2f}/kf {100 * r / max(r + w, 1):.0f}% ({r}/{r + w})")
    print(" | ".join(line), flush=True)


def temporal(te, scorer, vb, nkf, name, tol=(1.0, 1.5, 2.0)):
    """Multi-view check: keep a peak when the same point's peak at another keyframe has nearly the same offset from its
    projection (a right match's offset is the point's map error plus the pose error, slow across keyframes)."""
    recs = {}
    for p in te:
        S = scorer(pos_feats(p["F"])).reshape(2 * R + 1, 2 * R + 1)
        S[p["F"][0] <= -1] = -50
        uv, f = peak(S, p)
        if uv is None:
            continue
        ok = np.linalg.norm(uv - truth(p)) <= 2.0
        recs.setdefault((p["seed"], p["kf"][0], p["pid"]), []).append((p["kf"][1], uv - p["uv_proj"], ok, vb(f[None])[0]))
    for t in tol:
        for pmin in (-99, -2, 0):
            r = w = 0
            for k, lst in recs.items():
                lst.sort(key=lambda a: a[0])
                for i, (kf, off, ok, pv) in enumerate(lst):
                    if pv < pmin:
                        continue
                    nb = [b for j, b in enumerate(lst) if j != i and abs(j - i) <= 2 and b[3] >= pmin]
                    if any(np.linalg.norm(off - b[1]) <= t for b in nb):
                        r += ok; w += not ok
            print(f"  {name} temporal tol {t} px, verifier logit >= {pmin}: {r / nkf:.2f}/kf right, {w / nkf:.2f} wrong, {100 * r / max(r + w, 1):.0f}%")


def main():
    names, tr = load(sys.argv[1])
    _, te = load(sys.argv[2])
    nkf = len({(p["seed"], p["kf"]) for p in te})
    print(f"train pairs {len(tr)} ({len({p['seed'] for p in tr})} seeds), test pairs {len(te)}, {nkf} test keyframes, truth {TRUTH}")
    # render9 baseline
    for th in (0.6, 0.7, 0.8, 0.9):
        r = w = 0
        for p in te:
            if p["base_uv"] is not None and p["base_ncc"] >= th:
                if np.linalg.norm(p["base_uv"] - truth(p)) <= 2: r += 1
                else: w += 1
        print(f"NCC31 search >= {th}: right {r} ({r / nkf:.2f}/kf) wrong {w} precision {100 * r / max(r + w, 1):.0f}%")
    rng = np.random.default_rng(0)
    Xa, ya = stage_a_data(tr, rng)
    wts = np.where(ya == 1, (ya == 0).sum() / max((ya == 1).sum(), 1), 1.0)
    sa = logreg(Xa, ya, w=wts)
    ncc = lambda X: X[:, 0] * 10.0
    sc = clogit(clogit_data(tr, np.random.default_rng(0)))
    for name, scorer in (("clogit A", sc), ("learnt A", sa), ("ncc31 A", ncc)):
        _, Xb, Yb, _ = stage_b(tr, scorer)
        vb = logreg(Xb, Yb, lam=1.0)
        _, Xt, Yt, Kt = stage_b(te, scorer)
        print(f"{name}: test peaks {len(Yt)}, right {int(Yt.sum())} ({Yt.sum() / nkf:.2f}/kf, {100 * Yt.mean():.0f}%); train peaks right {100 * Yb.mean():.0f}%")
        curve(vb(Xt), Yt.astype(bool), nkf, f"  {name} + verifier")
        bb = boost(Xb, Yb)
        curve(bb(Xt), Yt.astype(bool), nkf, f"  {name} + boosted verifier")
        curve(Xt[:, 0], Yt.astype(bool), nkf, f"  {name} peak score")
        temporal(te, scorer, vb, nkf, name)
        curve(Xt[:, 2], Yt.astype(bool), nkf, f"  {name} margin")


if __name__ == "__main__":
    main()
