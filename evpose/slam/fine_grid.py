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
``klt_upsample_*`` defaults; ``klt_upsample`` itself stays off (indoor, the runaways)."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import fine_coords, robust_maximum, sensor_coords, to_uint8
from evpose.slam.features import track_features


def fine_to_uint8(img: np.ndarray, stride: int) -> np.ndarray:
    """The fine MCI ``img`` in 8 bits (``FeatureConfig.klt_upsample_scale_stride``): 0 is :func:`to_uint8`; ``stride``
    >= 1 takes its robust maximum (99.5th percentile of the non-zero pixels) from every ``stride``-th row and column
    only and scales in OpenCV (rounding, not truncating), the percentile over all ~360k pixels at 2x and the numpy
    scaling being most of the 5 ms :func:`to_uint8` spends there."""
    if stride <= 0:
        return to_uint8(img)
    img = np.asarray(img, dtype=np.float32)
    top = robust_maximum(np.abs(img[::stride, ::stride]))
    if top is None:
        top = robust_maximum(np.abs(img))
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
