"""Re-anchoring MCI-to-MCI tracks on the MCI they were born in (``FeatureConfig.klt_birth_anchor_px``, off).

Session 41 (pnp41) found that long KLT tracks drift ahead of the point they were born on (a third of the event-only
PnP inliers 3-20 px off, two thirds of them ahead along the image motion), so their map points are triangulated too
near and PnP places short keyframe steps; moving every track to its birth point's true projection at every MCI halves
the ATE, while correcting or dropping only the tracks within 3 px does not. Here, after each MCI-to-MCI step, each track
at least ``klt_birth_anchor_min_age`` MCIs old is tracked again by KLT from its birth MCI (the MCI it was detected or
re-found in, at its position there) into the current MCI, started at the chained position; when that lands within
``klt_birth_anchor_px`` of the chained position and passes the forward-backward test, the track moves there. Tracks
that fail are kept (or ended, ``klt_birth_anchor_drop``).

Measured (session 41, ``/tmp/s41/ta41/``: ``h.py`` = pnp41's harness reproducing ``evpose slam`` + ``evpose eval
--atlas --correct-scale``, ``ANCH_DIAG=1`` records every attempt against the true projection of the track's birth
ray-cast, ``adiag.py`` sums it up; ``pair.py`` pairs against main's defaults). ``klt_birth_anchor_px`` 8, min age 2,
keep on failure: ATE landing seeds 0 / 1 (3 s, 346x260) 1.09 / 1.97 -> 4.95 / 4.17 %; indoor seeds 0-9 1.96 -> 1.76 %
(paired -0.19 +- 0.32 points, 3 better and 7 worse; seed 5 4.32 -> 1.44 %, the rest 1.31-2.19 -> 1.44-2.51 %). The
keyframe step's shortness (pnp41's ``ana2.py``, h_rel = log step ratio against the map's three previous keyframes) is
not reduced: indoor -0.258 +- 0.070 -> -0.292 +- 0.067, landing -0.123 +- 0.032 -> -0.208 +- 0.040. It does not
re-anchor: of the tracks old enough, 17-37 % (landing 0, by age) / 43-60 % (indoor 1) pass the birth KLT within the
radius, and those move a median 0.20 / 0.25 px, ending closer to the truth for 39 / 48 % of them; the tracks 3-30 px
off stay there (median after 4.2-15.6 px). Ending the tracks that fail (``klt_birth_anchor_drop``) ends most old tracks:
landing 0 / 1 7.80 / 3.61 % (tracked 98.2 -> 91.1 / 92.9 %); indoor 0-9 1.96 -> 1.53 % (-0.43 +- 0.30, 6 better, all
ten within 2 %) but tracked as little as 78.1 % (against 87.3 %), and the share of time tracked from the events
(``visual_fraction`` of ``e.slam.json``) falls 0.280 -> 0.227 indoors (keeping: 0.260), 0.982 -> 0.660 on the landing:
the indoor gain is more coasting, as with ``FeatureConfig.klt_min_support_ratio``, not better tracks. Held-out indoor
seeds 10-12 (main's defaults run here, tag ``off``): 2.15 -> 1.59 % (2 better; tracked least 91.4 -> 79.7 %). Ending
only tracks at least 8 MCIs old (``klt_birth_anchor_min_age`` 8): landing 0 / 1 3.64 / 4.13 %, indoor 0-5 2.07 -> 1.77 %
(3 better, 3 worse; seed 3 1.31 -> 2.18 %). Why: the birth patch looks like the
drifted position, not like the birth point's true projection. NCC of the 11 px birth patch against the current MCI,
median at the chained position / at the truth (landing 0; indoor 1): tracks 0-1 px off 0.93 / 0.93 (0.90 / 0.85), 3-6
px off 0.74 / 0.56 (0.68 / -0.06), 6-10 px 0.74 / 0.37 (0.50 / -0.06), 10-30 px 0.69 / 0.31 (0.27 / -0.08); the truth
scores higher for 31 % (21 %) of the observations, and the best-NCC pixel within 10 px of the chained position is a
median 3.1-3.2 px from the truth even for tracks under 1 px off (closer than the chained position for 14 %). So the
tracks follow image structure that keeps its look while it moves off the birth point (corners that are not one scene
point: depth steps, occlusions, event-image edges), and no appearance test against the birth MCI, re-anchoring or
ending, can tell the drift (as session 21's affine ECC to the birth patch and session 20's keyframe re-anchoring found
on the landing). Nor is the indoor error a long track's drift (``agebin.py``, every live track of the same runs,
median error after 1 / 2 / 3-4 / 5-8 / 9-16 / 17+ MCI-to-MCI steps): indoor 1 2.30 / 3.96 / 4.59 / 4.08 / 2.70 / 3.16 px
(over 3 px 40 / 61 / 64 / 59 / 48 / 51 %), landing 0 0.96 / 1.39 / 1.67 / 2.09 / 2.35 / 4.50 px: indoors it is there
after the first one or two steps, on the landing it grows with age.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.slam.feature_config import FeatureConfig


@dataclass
class BirthAnchors:
    """Each live track's birth MCI and position there."""

    births: dict = field(default_factory=dict)
    """Track id -> (birth MCI index, birth pixel (2,) float32)."""
    images: dict = field(default_factory=dict)
    """Birth MCI index -> its uint8 MCI."""
    n_mci: int = 0
    """MCIs stepped into so far."""

    def register(self, ids: np.ndarray, uv: np.ndarray, img8: np.ndarray) -> None:
        """Record the tracks of ``ids`` not seen before as born in ``img8`` (the MCI ``uv`` lies in)."""
        new = [i for i, t in enumerate(ids.tolist()) if t not in self.births]
        if not new:
            return
        self.images[self.n_mci] = img8
        for i in new:
            self.births[int(ids[i])] = (self.n_mci, np.asarray(uv[i], np.float32).copy())

    def anchor(self, cur8: np.ndarray, ids: np.ndarray, new: np.ndarray, ok: np.ndarray,
               cfg: FeatureConfig) -> tuple[np.ndarray, np.ndarray]:
        """Positions ``new`` of the tracks ``ids`` after this MCI's step, re-anchored on their birth MCIs; returns (positions,
        ok) with the failed ones ended when ``cfg.klt_birth_anchor_drop``. Advances the MCI count and forgets dead tracks."""
        from evpose.slam.keyframe_search import klt_near

        self.n_mci += 1
        out, ok = new.copy(), ok.copy()
        live = {int(t) for t in ids[ok].tolist()}
        self.births = {t: b for t, b in self.births.items() if t in live}
        used = {b[0] for b in self.births.values()}
        self.images = {k: v for k, v in self.images.items() if k in used}
        groups: dict[int, list[int]] = {}
        for i in np.flatnonzero(ok):
            b = self.births.get(int(ids[i]))
            if b is not None and self.n_mci - b[0] >= cfg.klt_birth_anchor_min_age:
                groups.setdefault(b[0], []).append(int(i))
        for k in sorted(groups):
            idx = np.array(groups[k], np.int64)
            src = np.stack([self.births[int(ids[i])][1] for i in idx])
            found, good = klt_near(self.images[k], cur8, src, new[idx], cfg.klt_birth_anchor_px, cfg)
            out[idx[good]] = found[good]
            if cfg.klt_birth_anchor_drop:
                ok[idx[~good]] = False
        return out, ok
