"""Per (old point, post-turn keyframe) pair: score maps of several template comparisons over the 12 px search window.
feats.py CAPDIR SEEDS OUT.pkl  (PYTHONPATH at the s23-learn9 checkout). Pairs as render9's oracle.py (warp_slam 31 px
templates, search centred on the projection by the keyframe's PnP pose); truth both 'point' and 'tmpl' (render9's)."""
import os, pickle, sys
import cv2, numpy as np
sys.path.insert(0, "/tmp/s22/lead"); sys.path.insert(0, "/tmp/s22/render9")
import oracle, render
from evpose.slam.projection_search import ProjectionSearchConfig, search_patch
cv2.setNumThreads(1)
R = 12
PAD = 40
P = 31
SIZES = (31, 21, 11)


def orient(img, sigma=1.0):
    """Doubled-angle gradient field (polarity-free, magnitude-weighted) and gradient magnitude."""
    b = cv2.GaussianBlur(img, (0, 0), sigma)
    gx = cv2.Sobel(b, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(b, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    m = np.sqrt(gx * gx + gy * gy) + 1e-6
    return np.dstack([(gx * gx - gy * gy) / m, 2 * gx * gy / m]).astype(np.float32), m.astype(np.float32)


def window_map(img, tpl, cu, cv_, method=cv2.TM_CCOEFF_NORMED):
    s = tpl.shape[0]; r = s // 2
    h, w = img.shape[:2]
    y0, x0 = cv_ - R - r, cu - R - r
    if y0 < 0 or x0 < 0 or cv_ + R + r + 1 > h or cu + R + r + 1 > w:
        return None
    reg = np.ascontiguousarray(img[y0:cv_ + R + r + 1, x0:cu + R + r + 1])
    sc = cv2.matchTemplate(reg, np.ascontiguousarray(tpl), method)
    cv2.patchNaNs(sc, -1.0)
    return sc


def centre(a, s):
    o = (a.shape[0] - s) // 2
    return np.ascontiguousarray(a[o:o + s, o:o + s])


NAMES = ["ncc31", "ncc21", "ncc11", "blur31", "ori31", "ori15", "mag31", "ncc41", "ncc51", "signed31"] + [f"cell{k}" for k in range(9)] + [f"ocell{k}" for k in range(9)] + ["dist"]


def pair_maps(p, cache):
    T_src = p["tgt"]["kf_poses"].get(p["src"]["kf"], p["src"]["T_ba"])
    xyz = p["tgt"]["pts"][p["pid"]][0]
    W = render.warp_slam(p["src"]["img"], p["K"], T_src, p["tgt"]["T_pnp"], xyz, p["uv_src"], p["uv_proj"], P + 20)
    Ws = None
    if p["src"]["signed"] is not None and p["tgt"]["signed"] is not None:
        Ws = render.warp_slam(p["src"]["signed"], p["K"], T_src, p["tgt"]["T_pnp"], xyz, p["uv_src"], p["uv_proj"], P + 20)
    key = id(p["tgt"])
    if key not in cache:
        t = cv2.copyMakeBorder(p["tgt"]["img8"].astype(np.float32), PAD, PAD, PAD, PAD, cv2.BORDER_CONSTANT, value=0)
        o, m = orient(t)
        sg = None if p["tgt"]["signed"] is None else cv2.copyMakeBorder(p["tgt"]["signed"].astype(np.float32), PAD, PAD, PAD, PAD, cv2.BORDER_CONSTANT, value=0)
        cache.clear(); cache[key] = (t, cv2.GaussianBlur(t, (0, 0), 1.5), o, m, sg)
    t, tb, o, m, sg = cache[key]
    cu, cv_ = int(round(p["uv_proj"][0])) + PAD, int(round(p["uv_proj"][1])) + PAD
    Wo, Wm = orient(W)
    maps = []
    for s in SIZES:
        maps.append(window_map(t, centre(W, s), cu, cv_))
    maps.append(window_map(tb, centre(cv2.GaussianBlur(W, (0, 0), 1.5), 31), cu, cv_))
    maps.append(window_map(o, centre(Wo, 31), cu, cv_))
    maps.append(window_map(o, centre(Wo, 15), cu, cv_))
    maps.append(window_map(m, centre(Wm, 31), cu, cv_))
    maps.append(window_map(t, centre(W, 41), cu, cv_))
    maps.append(window_map(t, W, cu, cv_))
    if Ws is not None and sg is not None and float(Ws.std()) > 0:
        maps.append(window_map(sg, centre(Ws, 31), cu, cv_))
    else:
        maps.append(np.zeros((2 * R + 1, 2 * R + 1), np.float32))
    c0 = W.shape[0] // 2
    for img, src in ((t, W), (o, Wo)):  # 3 x 3 cells of 11 px tiling the 31 px template: a learnt spatial weighting
        for dy in (-10, 0, 10):
            for dx in (-10, 0, 10):
                cell = np.ascontiguousarray(src[c0 + dy - 5:c0 + dy + 6, c0 + dx - 5:c0 + dx + 6])
                maps.append(window_map(img, cell, cu + dx, cv_ + dy) if float(cell.std()) > 0 else np.full((2 * R + 1, 2 * R + 1), 0, np.float32))
    if any(x is None for x in maps):
        return None
    yy, xx = np.mgrid[-R:R + 1, -R:R + 1]
    h, w = p["tgt"]["img8"].shape
    u, v = xx + cu - PAD, yy + cv_ - PAD
    inside = (u >= 2) & (u < w - 2) & (v >= 2) & (v < h - 2)
    for mm in maps:
        mm[~inside] = -1.0
    maps.append((np.hypot(xx, yy) / R).astype(np.float32))
    F = np.stack(maps).astype(np.float32)
    # baseline: render9's search (NCC >= threshold, uniqueness 0.9) at several thresholds, recorded by its best NCC
    tpl = centre(W, P)
    cfg = ProjectionSearchConfig(min_ncc=-1.0, max_second_ratio=0.9, min_texture=4.0)
    uv, best = search_patch(p["tgt"]["img8"].astype(np.float32), tpl, p["uv_proj"], R, cfg)
    Jxx, Jxy, Jyy = render.tensor(centre(W, P), 1.0, 5.0)
    c = P // 2
    a, b, d = float(Jxx[c, c]), float(Jxy[c, c]), float(Jyy[c, c])
    disc = np.sqrt((a - d) ** 2 + 4 * b * b)
    l1, l2 = (a + d + disc) / 2, (a + d - disc) / 2
    coh = (l1 - l2) / max(l1 + l2, 1e-12)
    A = cv2.matchTemplate(W, centre(W, P), cv2.TM_CCOEFF_NORMED); cv2.patchNaNs(A, -1.0)
    a0 = A.shape[0] // 2
    A2 = A.copy(); A2[a0 - 2:a0 + 3, a0 - 2:a0 + 3] = -1
    reg = np.ascontiguousarray(t[cv_ - R - 15:cv_ + R + 16, cu - R - 15:cu + R + 16]).astype(np.float16)
    return dict(F=F, tpl=centre(W, P).astype(np.float16), reg=reg, auto_max2=float(A2.max()), auto_cnt=int((A2 > 0.8).sum()), off=np.array([cu - PAD, cv_ - PAD], float), uv_proj=p["uv_proj"].copy(), uv_true=p["uv_true"].copy(), uv_tmpl=p["uv_tmpl"].copy(),
                seed=p["seed"], kf=p["kf"], pid=p["pid"], base_uv=uv, base_ncc=best, coh=coh, tstd=float(tpl.std()))


def main():
    capdir, seeds, out = sys.argv[1], [int(s) for s in sys.argv[2].split(",")], sys.argv[3]
    # pairs_for_seed reads render9's capture dir and ranks best sources (unused here, slow): redirect and skip
    oracle.best_sources = lambda *a, **k: []
    import builtins
    _open = builtins.open
    res = []
    for seed in seeds:
        fn = f"{capdir}/landing_seed{seed}.pkl"
        if not os.path.exists(fn):
            print("missing", fn, flush=True); continue
        oracle.open = lambda f, *a, **k: _open(f.replace("/tmp/s22/render9/cap", capdir), *a, **k)
        prs = oracle.pairs_for_seed(seed)
        cache = {}
        n0 = len(res)
        for p in prs:
            r = pair_maps(p, cache)
            if r is not None:
                res.append(r)
        print(seed, len(prs), "pairs", len(res) - n0, "kept", len({p["kf"] for p in prs}), "kfs", flush=True)
        del prs
    pickle.dump(dict(names=NAMES, pairs=res), open(out, "wb"))


if __name__ == "__main__":
    main()
