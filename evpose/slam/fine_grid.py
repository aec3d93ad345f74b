"""KLT on MCIs rendered on a grid finer than the sensor's (``FeatureConfig.klt_upsample``): the fine image's 8-bit form
and the tracking, in sensor pixels. Measurements in the Session 24 notes of :mod:`evpose.slam.features`."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from evpose.slam.config import FeatureConfig
from evpose.slam.event_image import fine_coords, sensor_coords, to_uint8
from evpose.slam.features import track_features


def fine_to_uint8(img: np.ndarray, stride: int) -> np.ndarray:
    """The fine MCI ``img`` in 8 bits (``FeatureConfig.klt_upsample_scale_stride``): 0 is :func:`to_uint8`; ``stride``
    >= 1 takes its robust maximum (99.5th percentile of the non-zero pixels) from every ``stride``-th row and column
    only and scales in OpenCV (rounding, not truncating), the percentile over all ~360k pixels at 2x and the numpy
    scaling being most of the 5 ms :func:`to_uint8` spends there."""
    if stride <= 0:
        return to_uint8(img)
    img = np.asarray(img, dtype=np.float32)
    mag = np.abs(img[::stride, ::stride])
    nz = mag[mag > 0]
    if nz.size == 0:
        mag = np.abs(img)
        nz = mag[mag > 0]
        if nz.size == 0:
            return np.zeros(img.shape, np.uint8)
    top = float(np.percentile(nz, 99.5))
    top = top if top > 0 else float(nz.max())
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
