"""table.py RUN...: per need.py run, mean / median / within 2 % of landing seeds 0-23, paired difference against the
defaults (/tmp/s22/render9/base.json) mean +- s.e., better / worse, observations kept per post-2 s keyframe and realised
precision."""
import json, sys
import numpy as np
base = json.load(open("/tmp/s22/render9/base.json"))
print(f"{'run':12s} {'Q':>5s} {'P':>5s} {'mode':>5s} {'obs/kf':>6s} {'right/kf':>8s} {'prec':>5s} {'mean':>6s} {'median':>6s} {'w2':>3s} "
      f"{'paired':>15s} better")
for name in sys.argv[1:]:
    d = json.load(open(f"/tmp/s23/need9/{name}.json"))
    seeds = [s for s in d["rows"] if s in base["rows"]]
    x = np.array([base["rows"][s]["ate"] for s in seeds]); y = np.array([d["rows"][s]["ate"] for s in seeds])
    dd = y - x
    t = d["totals"]
    print(f"{name:12s} {d['Q']:5.2f} {d['P']:5.2f} {d['wrong_mode']:>5s} {t['added'] / t['keyframes']:6.2f} "
          f"{(t['added'] - t['wrong']) / t['keyframes']:8.2f} {1 - t['wrong'] / max(t['added'], 1):5.2f} {y.mean():6.3f} "
          f"{np.median(y):6.2f} {int((y <= 2).sum()):3d} {dd.mean():+7.3f} +- {dd.std(ddof=1) / np.sqrt(len(dd)):.3f} "
          f"{int((dd < 0).sum()):2d}/{int((dd > 0).sum()):2d}  (kept {t['added'] / len(seeds):.1f} a run, worst {y.max():.2f})")
