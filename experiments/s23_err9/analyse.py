"""Error distribution of the logged in-situ revisit matches (record.py's /tmp/s23/err9/seedN.json): analyse.py SEEDS."""
import json, sys, itertools
import numpy as np
seeds = sys.argv[1].split(",")
R = []
kfn = []
for s in seeds:
    d = json.load(open(f"/tmp/s23/err9/seed{s}.json"))
    print(f"seed {s}: ATE {d['ate']:.3f} %, matches {len(d['matches'])}, keyframes searched {len(d['kfs'])}, "
          f"post-2 s {sum(k['t'] >= 2.0 for k in d['kfs'])}")
    for m in d["matches"]:
        m["seed"] = int(s); R.append(m)
    kfn += [k["n"] for k in d["kfs"] if k["n"] > 0]
print("matches", len(R), "with truth", sum("truth" in m for m in R), "keyframes with matches", len(kfn),
      "per such keyframe", np.bincount(kfn).tolist())
T = [m for m in R if "truth" in m]
for m in T:
    uv, q, p = (np.array(m[k]) for k in ("uv", "truth", "proj"))
    m["e"] = float(np.linalg.norm(uv - q)); m["ep"] = float(np.linalg.norm(p - q)); m["d_proj"] = float(np.linalg.norm(uv - p))
    m["ev"] = (uv - q).tolist()
    m["first"] = m["last_t"] < 1.6 and m["cons"] < 3.0
    m["post"] = m["t"] >= 2.0
    if "normal" in m:
        n = np.array(m["normal"]); v = uv - q
        m["across"] = float(abs(v @ n)); m["along"] = float(abs(v[0] * n[1] - v[1] * n[0]))
        pv = p - q
        m["p_across"] = float(abs(pv @ n)); m["p_along"] = float(abs(pv[0] * n[1] - pv[1] * n[0]))


def summ(name, S):
    if not S:
        print(f"{name:34s} n 0"); return
    e = np.array([m["e"] for m in S]); ep = np.array([m["ep"] for m in S])
    print(f"{name:34s} n {len(S):3d}  match<=1/2/3 px {np.mean(e<=1):.0%} {np.mean(e<=2):.0%} {np.mean(e<=3):.0%} med {np.median(e):.2f}"
          f" | proj<=1/2/3 {np.mean(ep<=1):.0%} {np.mean(ep<=2):.0%} {np.mean(ep<=3):.0%} med {np.median(ep):.2f}")


summ("all", T)
summ("post-2.0 s keyframes", [m for m in T if m["post"]])
summ("first-leg consistent (need9 pop.)", [m for m in T if m["first"]])
summ("  ... at post-2.0 s keyframes", [m for m in T if m["first"] and m["post"]])
summ("other old points", [m for m in T if not m["first"]])
summ("  last obs < 1.6 s, inconsistent", [m for m in T if not m["first"] and m["last_t"] < 1.6])
summ("  last obs >= 1.6 s", [m for m in T if m["last_t"] >= 1.6])
right = [m for m in T if m["e"] <= 2]
print("right (<=2 px): error median %.2f px, mean %.2f; need9's model (0.7 px per axis): median 0.82" %
      (np.median([m["e"] for m in right]), np.mean([m["e"] for m in right])) if right else "no right")
W = [m for m in T if m["e"] > 2]
print("wrong (>2 px):", len(W), "error quantiles 25/50/75/max", np.round(np.percentile([m["e"] for m in W], [25, 50, 75, 100]), 1).tolist(),
      "share > 10 px %.0f%%" % (100 * np.mean([m["e"] > 10 for m in W])))
Wn = [m for m in W if "across" in m]
ang = np.degrees(np.arctan2([m["across"] for m in Wn], [m["along"] for m in Wn]))
print("  offset angle from the edge (0 = along, 90 = across): median %.0f deg, within 30 deg of along %d / %d, beyond 60 %d"
      % (np.median(ang), np.sum(ang < 30), len(Wn), np.sum(ang > 60)))
print("  across / along median %.1f / %.1f px (proj's own for these %.1f / %.1f)" % (
    np.median([m["across"] for m in Wn]), np.median([m["along"] for m in Wn]),
    np.median([m["p_across"] for m in Wn]), np.median([m["p_along"] for m in Wn])))
near = [m["d_proj"] < m["ep"] for m in W]
print("  match nearer the SLAM projection than the truth is (|uv-proj| < |truth-proj|): %d / %d; |uv-proj| median %.1f, |truth-proj| median %.1f"
      % (sum(near), len(W), np.median([m["d_proj"] for m in W]), np.median([m["ep"] for m in W])))
print("  match nearer the projection than to the truth (|uv-proj| < |uv-truth|): %d / %d; within 2 px of the projection %d" %
      (sum(m["d_proj"] < m["e"] for m in W), len(W), sum(m["d_proj"] <= 2 for m in W)))
print("  match moved the estimate towards the truth (|uv-truth| < |proj-truth|): all %d / %d, wrong %d / %d" %
      (sum(m["e"] < m["ep"] for m in T), len(T), sum(m["e"] < m["ep"] for m in W), len(W)))
# within a keyframe: do errors share a direction?
cos, cosw = [], []
by = {}
for m in T:
    by.setdefault((m["seed"], m["kf"]), []).append(m)
for ms in by.values():
    for a, b in itertools.combinations(ms, 2):
        va, vb = np.array(a["ev"]), np.array(b["ev"])
        c = float(va @ vb / max(np.linalg.norm(va) * np.linalg.norm(vb), 1e-9))
        cos.append(c)
        if a["e"] > 2 and b["e"] > 2:
            cosw.append(c)
print("keyframes with >= 2 matches (with truth):", sum(len(v) >= 2 for v in by.values()), "pairs", len(cos),
      "error-vector cosine median %.2f, > 0.7: %d, < -0.7: %d" % (np.median(cos), np.sum(np.array(cos) > 0.7), np.sum(np.array(cos) < -0.7)) if cos else "")
if cosw:
    print("  both wrong: pairs %d, cosine median %.2f, > 0.7: %d" % (len(cosw), np.median(cosw), np.sum(np.array(cosw) > 0.7)))
print("per match: seed kf t  first  e  ep  d_proj  angle")
for m in sorted(T, key=lambda m: (m["seed"], m["kf"])):
    a = np.degrees(np.arctan2(m.get("across", np.nan), m.get("along", np.nan)))
    print(f"  {m['seed']:2d} {m['kf']:3d} {m['t']:.2f} {int(m['first'])} last {m['last_t']:.2f} cons {m['cons']:.1f}  e {m['e']:5.1f} ep {m['ep']:5.1f} dproj {m['d_proj']:5.1f} ang {a:3.0f}")
cosp, cosd = [], []
for ms in by.values():
    for a, b in itertools.combinations(ms, 2):
        pa, pb = (np.array(x["proj"]) - np.array(x["truth"]) for x in (a, b))
        cosp.append(float(pa @ pb / max(np.linalg.norm(pa) * np.linalg.norm(pb), 1e-9)))
for m in T:
    v, pv = np.array(m["ev"]), np.array(m["proj"]) - np.array(m["truth"])
    m["cosd"] = float(v @ pv / max(np.linalg.norm(v) * np.linalg.norm(pv), 1e-9))
if cosp:
    print("same pairs, the projections' errors (drift): cosine median %.2f, > 0.7: %d" % (np.median(cosp), np.sum(np.array(cosp) > 0.7)))
cd = np.array([m["cosd"] for m in W])
print("wrong: cosine of the match's error with the projection's error (drift direction): median %.2f, > 0.5: %d / %d, < -0.5: %d"
      % (np.median(cd), np.sum(cd > 0.5), len(cd), np.sum(cd < -0.5)))
cd = np.array([m["cosd"] for m in T if m["e"] <= 2])
print("right: same cosine median %.2f" % np.median(cd))
pre = [m for m in T if not m["post"]]
summ("matches at keyframes before 2.0 s", pre)
