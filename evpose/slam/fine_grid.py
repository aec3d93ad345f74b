"""KLT on MCIs rendered on a grid finer than the sensor's (``FeatureConfig.klt_upsample``): the fine image's 8-bit form
and the tracking, in sensor pixels. Why and how accurate: the Session 24 notes of :mod:`evpose.slam.features`.

Session 24, fitting the fine pass into 30 ms per MCI (``/tmp/s24/fine9``: ``cpubench.py`` main-thread CPU of MCI and
tracking, median of the runs' medians over landing seeds 0-3, variants alternating in one process; ``u8bench.py`` /
``kltbench.py`` synthetic; ``agg.py`` / ``pj.py`` the ATE from ``/tmp/s22/lead/exp.py``). All at 2x, sigma 0.5 sensor
px. CPU per MCI: defaults 22.9 ms; 47 px window, 3 levels, full 8-bit scaling (the session-24 first measurement) 42.6;
with the robust maximum from every 2nd row and column and OpenCV scaling (:func:`fine_to_uint8`) 42.0 (synthetic 5.9 ->
1.1 ms; the real MCIs have few non-zero pixels, so the percentile costs less than the first estimate of 5 ms); with that
and a 41 / 35 / 31 px window 29.7 / 28.3 / 29.4 (the 47 px window's KLT is where the cost was: forward and backward
15.7 ms synthetic, 7.4 at 35 px); 35 px with 2 levels 21.7. Seeds 4-7 (``cpubench2.py``, the new defaults): 22.6 / 44.2 (47 px, full scaling) / 29.3. Landing ATE, paired per seed against the 47 px variant
(``/tmp/s24/sr9``: ``f2s05*.json``) and the defaults under the defaults and session 23's four perturbations
(``TrackingConfig.ba_huber_px`` 1.9 / 2.1, ``reprojection_threshold_px`` 2.4 / 2.6), seeds 0-23 / 24-47, 35 px and
stride 2: 1.59 / 1.96 / 2.04 / 1.77 / 1.93 % and 1.86 / 1.91 / 1.81 / 2.18 / 1.42 % (47 px: 2.10 / 2.44 / 2.12 / 2.12 /
1.55 and 1.78 / 1.80 / 1.76 / 1.98 / 1.81; defaults 1.80 / 2.55 / 2.00 / 2.68 / 1.99 and 2.09 / 1.90 / 1.84 / 2.39 /
3.04); over the 240 runs 1.85 % against 1.95 and 2.23, median 1.41 / 1.52 / 1.69, within 2 % 204 / 204 / 163, over 5 %
12 / 15 / 11 (seeds 10 and 36 under four to five of the settings each), paired -0.10 +- 0.13 points against 47 px (142
better), -0.38 +- 0.15 against the defaults (169 better). Stride 2 alone (47 px), defaults, seeds 0-23: 2.04 % (20
within 2 %) against 2.10 (20). 41 px, defaults: 1.33 % (24 within 2 %) and 2.30 % (19; seeds 26 / 36 9.2 / 10.8 %).
35 px with 2 levels: 8.53 / 8.54 % (0 within 2 %; tracked from the events 0.97 -> 0.46 of the time). Indoor event-only seeds 0-7, 35 px: 8.93 % (defaults 6.84, 47 px 11.23). So 35 px and stride 2 are the
``klt_upsample_*`` defaults; ``klt_upsample`` itself stays off (indoor, the runaways).

Session 25, why indoor got worse and the rule that now turns the fine grid on (``/tmp/s25/auto9``: ``steprec.py``
re-tracks every MCI-to-MCI step of a default run on both grids from the same start positions, the step's truth being the
ray-cast of the start pixel at the previous MCI's true pose projected at the current one, ``an.py``-``an5.py`` sum it
up; ``fail.py`` splits the lost steps by how KLT failed; ``exp.py`` is ``/tmp/s22/lead/exp.py`` with the normalised RPE;
``pj.py`` / ``agg.py`` pair the runs; ``cpubench.py`` the CPU). Indoor seeds 0-7 (195516 track steps) against landing
seeds 0, 4, 10, 17 (37874), 2x grid against the sensor grid: the fine grid keeps fewer indoor steps, 0.562 -> 0.486
(map-point tracks 0.823 -> 0.726), where on the landing it keeps more, 0.654 -> 0.671, and it makes the indoor steps no
more precise (steps both keep, median across-flow error 0.396 -> 0.387 px, landing 0.239 -> 0.192; tracks on patches
with over 4 times the mean event mass 0.287 -> 0.286 against 0.205 -> 0.164). What decides it is the MCI's event count:
indoor MCIs hold 1800 events (median, 5-95 % 1200-8900; 6 ms windows, 3.9 % of the pixels lit), landing ones 12462 (at
least 3948; 25-56 ms, 14 %). By events per MCI (both scenarios): under 3000 (only indoor) the fine grid keeps 0.81-0.84
of the sensor grid's steps, 0.76-0.85 of the map-point steps and 0.89-0.91 of those within 1 px of the truth; from 3000
on 0.94-1.02 / 0.92-0.95 / 0.99-1.15. The lost steps sit on patches with few events (indoor, under half the MCI's mean
event mass in the 7 px square: kept 0.581 -> 0.429; 0.5-4 times 0.509 -> 0.433; over 4 times 0.648 -> 0.644), and KLT
stops converging there (OpenCV's status: too little gradient in the window once the events are splatted at sigma 0.5 on
the finer grid) rather than failing the forward-backward test: indoor seed 0, MCIs under 3000 events, forward not
converged 0.026 -> 0.056 of the steps, backward 0.192 -> 0.271, over the forward-backward threshold 0.347 -> 0.337
(landing seeds 0, 4: forward 0.025-0.045 -> 0.018-0.032, backward 0.027-0.051 -> 0.017-0.038). So the sparse noise the
session-24 note suspected is not taking tracks over: the fine grid drops more of the tracks on empty patches, not fewer.
(Events with no other in their 3x3 sensor pixels over the window, raw positions, mostly background activity: 9-13 % of
an indoor window's, 3.5 % of a dense landing one's, 9-12 % in the landing's turn; so this share does not tell the two
apart.) Even the indoor MCIs with 6000-13000 events gain nothing: their steps are already at 0.10 px across the flow,
and the fine grid keeps 0.87-0.91 of them.

Judging each MCI by its own events (``klt_upsample_min_events_per_px`` with ``klt_upsample_warmup_mcis`` 0): 0.035
events per pixel (3150 at 346x260; nearly every landing MCI) gives landing seeds 0-23 1.59 % (the fine grid always:
1.59, seed 6 only differs) but indoor 0-7 8.04 % (6.84 off, 8.93 always; seeds 0 / 7 12.78 / 16.30 %); 0.1, which leaves
the landing's turn (3000-9000 events) on the sensor grid: landing 2.29 % (16 within 2 %; paired against off +0.49 +-
0.26 points), indoor 6.64 %. So the turn needs the fine grid, and switching per MCI leaves enough fine steps indoors to
move its chaotic outcome. Judging once per recording (the defaults): the first 10 MCIs' median is 0.039-0.089 events per
pixel indoors (seeds 0-11; the rooms start denser than they go on) and 0.185-0.247 on the landing (seeds 0-71,
``warmup.py``), so 0.15 splits them; the warm-up tracks on the sensor grid. Indoor then stays bit-identical to the
sensor grid (seeds 0-7 6.84 %, held-out 8-11 7.98 %; the fine grid always there: 8.30 %, 2 of 4 worse), and the landing,
paired against off under the defaults and session 23's four perturbations (``TrackingConfig.ba_huber_px`` 1.9 / 2.1,
``reprojection_threshold_px`` 2.4 / 2.6), seeds 0-23 1.44 / 1.67 / 1.67 / 1.69 / 2.00 % (off 1.80 / 2.55 / 2.00 / 2.68 /
1.99, always 1.59 / 1.96 / 2.04 / 1.77 / 1.93), 24-47 1.70 / 1.70 / 1.63 / 1.80 / 1.71 % (off 2.09 / 1.90 / 1.84 / 2.39
/ 3.04, always 1.86 / 1.91 / 1.81 / 2.18 / 1.42); over the 240 runs 1.70 % (off 2.23, always 1.85), median 1.38 (1.69,
1.41), within 2 % 209 (163, 204), over 5 % 7 (11, 12; no seed more than twice), paired -0.53 +- 0.14 points against off
(177 better), -0.15 +- 0.12 against always (115 better). With the defaults, seeds 0-23 1.44 % (24 of 24 within 2 %,
worst 1.98; seed 10 4.58 -> 1.35), 24-47 1.70 % (19; worst 4.72), 48-71 2.17 -> 1.82 % (11 -> 20 within 2 %; paired
-0.35 +- 0.22 points, 21 better; seed 66 4.45 -> 8.35 %). Event-inertial E-I-C2 (``exp.py ... c2``), landing seeds 0-23:
ATE 0.82 -> 0.94 % (paired +0.12 +- 0.13, 10 better; always: 1.00 %), 23 of 24 within 2 % either way, RPE at most 0.0050
-> 0.0034 m/m and 0.0022 -> 0.0020 deg/m (always: 0.0033 / 0.0020); indoor seeds 0-7 unchanged (ATE 19.60 %, RPE at most
0.0067 m/m, 0.0047 deg/m). Main-thread CPU per MCI (``cpubench.py``, median of the runs' medians, variants alternating
in one process): landing seeds 0-3 off 22.8 ms, always 29.1, the rule 28.6; indoor seeds 0-1 15.1 / 21.7 / 15.0. The
warm-up's length: see ``FeatureConfig.klt_upsample_warmup_mcis``.

Session 26 (``/tmp/s26/speed26``; module notes of :mod:`evpose.slam.mci`): the MCI stage in numba and KLT without its
unread error pass, outputs bit for bit the same, give the rule landing seeds 0-3 31.1 -> 25.8 ms per MCI (means 36.2 ->
30.8; main measured alongside on a loaded machine, its quiet figure being the 28.6 above), indoor seeds 0-1 16.4 ->
12.2 ms. The fine image's 8-bit scaling reads ``|img|`` in place
(:func:`fine_to_uint8`; :func:`evpose.slam.event_image.robust_maximum` with a stride). Its KLT, forward and backward on
the 692x520 images, is now the largest part of a landing MCI that is not a keyframe (about 9 of 25 ms).
Session 26, a rolling rule for recordings that start sparse (``/tmp/s26/lead``; not kept): the median over the last 10
MCIs instead of the first 10, the fine grid on once it reaches the floor. On the simulated recordings it changes
nothing: the indoor rooms' rolling median peaks at 0.094-0.119 events per pixel (seeds 0-11, event-only and E-I-C2
alike, ``dens.py``), the landing passes at its warm-up. On a landing whose first 1.2 s keep 40 % of their events (a dim
start, ``dim.py``, seeds 0-7) 4.38 -> 4.36 % (seeds 4 and 5 only moved; the full-brightness runs 1.44 % on 0-23: the dim
start itself costs seeds 4, 5 and 7, 7-11 %), and on the indoor room followed at once by the landing (``splice.py``, the
landing part's maps) 6.83 -> 7.80 % (seeds 2 and 3 worse, 0 and 6 better): no gain to show for the change."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import fine_coords, robust_maximum, sensor_coords, to_uint8
from evpose.slam.features import FrontendTracks, track_features


def use_fine_grid(fe: FrontendTracks, n_events: int, n_pixels: int, cfg: FeatureConfig) -> bool:
    """Whether the MCI of ``n_events`` events on a sensor of ``n_pixels`` pixels gets a fine image
    (``FeatureConfig.klt_upsample``, ``klt_upsample_min_events_per_px``, ``klt_upsample_warmup_mcis``); call once per
    MCI, in order: the warm-up's state lives in ``fe``."""
    if cfg.klt_upsample <= 1.0:
        return False
    floor = float(cfg.klt_upsample_min_events_per_px)
    if floor <= 0.0:
        return True
    density = n_events / max(n_pixels, 1)
    if cfg.klt_upsample_warmup_mcis <= 0:
        return density >= floor
    if fe.fine_on is None:
        fe.fine_density.append(density)
        if len(fe.fine_density) < cfg.klt_upsample_warmup_mcis:
            return False
        fe.fine_on = bool(np.median(fe.fine_density) >= floor)
    return fe.fine_on


def fine_to_uint8(img: np.ndarray, stride: int) -> np.ndarray:
    """The fine MCI ``img`` in 8 bits (``FeatureConfig.klt_upsample_scale_stride``): 0 is :func:`to_uint8`; ``stride``
    >= 1 takes its robust maximum (99.5th percentile of the non-zero pixels) from every ``stride``-th row and column
    only and scales in OpenCV (rounding, not truncating), the percentile over all ~360k pixels at 2x and the numpy
    scaling being most of the 5 ms :func:`to_uint8` spends there."""
    if stride <= 0:
        return to_uint8(img)
    img = np.asarray(img, dtype=np.float32)
    top = robust_maximum(img, stride)  # |img| read in place (session 26; bit for bit the same)
    if top is None:
        top = robust_maximum(img)
        if top is None:
            return np.zeros(img.shape, np.uint8)
    if (img < 0).any():  # signed: 0 -> 128, saturating at +-top
        return np.clip(np.rint(128.0 + img * np.float32(127.0 / top)), 1, 255).astype(np.uint8)
    return cv2.convertScaleAbs(img, alpha=255.0 / top)


def fine_klt_config(cfg: FeatureConfig) -> FeatureConfig:
    """``cfg`` for KLT on the grid ``cfg.klt_upsample`` times finer (``FeatureConfig.klt_upsample``): its window,
    levels and forward-backward threshold in fine pixels."""
    s = float(cfg.klt_upsample)
    win = int(cfg.klt_upsample_window_px) or int(np.ceil(cfg.klt_window_px * s))
    return replace(cfg, klt_window_px=win | 1, klt_levels=int(cfg.klt_upsample_levels), klt_max_bidir_error_px=cfg.klt_max_bidir_error_px * s)


def track_features_fine(prev_fine8: np.ndarray, cur_fine8: np.ndarray, pts: np.ndarray, cfg: FeatureConfig,
                        guess: np.ndarray | None = None, min_ncc: float = 0.0, prev8: np.ndarray | None = None,
                        cur8: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`track_features` on MCIs rendered ``cfg.klt_upsample`` times finer (``MciResult.fine_image``); ``pts``,
    ``guess`` and the result in sensor pixels, the forward-backward threshold still ``klt_max_bidir_error_px`` of them.
    With ``cfg.klt_upsample_refine`` the sensor-grid MCIs ``prev8`` -> ``cur8`` are tracked first and the fine pass,
    single-level, starts at their result (the tracks it loses stay lost)."""
    s = float(cfg.klt_upsample)
    fcfg = fine_klt_config(cfg)
    g = None if guess is None else fine_coords(guess, s).astype(np.float32)
    back = False
    if cfg.klt_upsample_refine and prev8 is not None and cur8 is not None:
        coarse, ok0 = track_features(prev8, cur8, pts, cfg, guess=guess, min_ncc=min_ncc)
        g, back, fcfg = fine_coords(coarse, s).astype(np.float32), True, replace(fcfg, klt_levels=0)
    new, ok = track_features(prev_fine8, cur_fine8, fine_coords(pts, s).astype(np.float32), fcfg, guess=g, guess_back=back, min_ncc=min_ncc)
    if back:
        ok &= ok0
    new = sensor_coords(new, s).astype(np.float32)
    w, h = (cur_fine8.shape[1] + 0.5) / s - 0.5, (cur_fine8.shape[0] + 0.5) / s - 0.5  # the sensor's last pixel centre
    ok &= (new[:, 0] >= 0) & (new[:, 0] <= w - 1) & (new[:, 1] >= 0) & (new[:, 1] <= h - 1)
    return new, ok
