"""Image panels: SP-TS per polarity, TDF with the reprojected map points, kept vs removed events."""

from __future__ import annotations

import enum

import cv2
import numpy as np

from app.frame import Frame
from app.frame_cache import quantize
from evpose.core.events import EventArray


class OverlayColour(str, enum.Enum):
    """What colours the reprojected contour points on the TDF panel."""

    RESIDUAL = "residual"
    WEIGHT = "weight"
    POLARITY = "predicted polarity"


def _scale_for(img_w: int) -> int:
    # Small sensors are upscaled (nearest) so single pixels stay visible in the browser.
    return max(1, 320 // max(1, img_w))


def colormap(img: np.ndarray, cmap: int, vmin: float = 0.0, vmax: float = 1.0) -> np.ndarray:
    """float (H, W) in [vmin, vmax], or uint8 already quantized (``frame_cache.quantize``), -> RGB uint8 (H, W, 3)."""
    if np.asarray(img).dtype == np.uint8:
        q = np.ascontiguousarray(img)
    else:
        a = np.clip((np.asarray(img, np.float32) - vmin) / max(vmax - vmin, 1e-12), 0.0, 1.0)
        q = (a * 255.0).astype(np.uint8)
    bgr = cv2.applyColorMap(q, cmap)
    return np.ascontiguousarray(bgr[..., ::-1])


def upscale(rgb: np.ndarray) -> np.ndarray:
    s = _scale_for(rgb.shape[1])
    return rgb if s == 1 else cv2.resize(rgb, (rgb.shape[1] * s, rgb.shape[0] * s), interpolation=cv2.INTER_NEAREST)


def ts_image(ts: np.ndarray, positive: bool) -> np.ndarray:
    return upscale(colormap(ts, cv2.COLORMAP_HOT if positive else cv2.COLORMAP_OCEAN))


def tdf_image(frame: Frame, colour_by: OverlayColour = OverlayColour.RESIDUAL) -> np.ndarray:
    """The TDF in grey with each used map point drawn where it projects, coloured by residual/weight/polarity."""
    rgb = np.repeat(quantize(frame.tdf)[..., None], 3, axis=2)
    rgb = upscale(rgb)
    uv = frame.projected_uv
    if uv is None or len(uv) == 0:
        return rgb
    s = _scale_for(frame.tdf.shape[1])
    if colour_by == OverlayColour.POLARITY and frame.predicted_polarity is not None:
        pol = frame.predicted_polarity
        cols = np.where(pol[:, None] > 0, [230, 40, 40], np.where(pol[:, None] < 0, [40, 90, 230], [240, 200, 0]))
    else:
        vals = frame.weights if colour_by == OverlayColour.WEIGHT and frame.weights is not None else frame.residuals
        if vals is None:
            vals = np.zeros(len(uv), np.float32)
        # Residuals: green (0, on the edge) -> red (1, far); weights: red (0) -> green (1).
        a = np.clip(np.asarray(vals, np.float32), 0.0, 1.0)
        if colour_by == OverlayColour.WEIGHT:
            a = 1.0 - a
        cols = np.stack([255 * a, 255 * (1 - a), np.full_like(a, 40)], axis=1)
    h, w = rgb.shape[:2]
    finite = np.isfinite(uv).all(axis=1)  # points that did not project (failed registration) are not drawn
    uv, cols = uv[finite], np.asarray(cols)[finite]
    px = np.round((uv[:, 0] + 0.5) * s - 0.5).astype(np.int64)
    py = np.round((uv[:, 1] + 0.5) * s - 0.5).astype(np.int64)
    r = max(1, s // 2)
    cols = cols.astype(np.uint8)
    # Each point is a (2r-1)-pixel square, drawn for all points at once per offset (no per-point Python loop).
    for dy in range(-r + 1, r):
        for dx in range(-r + 1, r):
            x, y = px + dx, py + dy
            ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            rgb[y[ok], x[ok]] = cols[ok]
    return rgb


def events_image(kept: EventArray, removed: EventArray, width: int, height: int) -> np.ndarray:
    """Kept ON red, kept OFF blue, removed events grey, on black."""
    rgb = np.zeros((height, width, 3), np.uint8)
    for ev, on, off in ((removed, (110, 110, 110), (110, 110, 110)), (kept, (235, 60, 50), (60, 120, 245))):
        if len(ev) == 0:
            continue
        ok = (ev.x < width) & (ev.y < height)
        x, y, p = ev.x[ok], ev.y[ok], ev.p[ok]
        rgb[y[p > 0], x[p > 0]] = on
        rgb[y[p < 0], x[p < 0]] = off
    return upscale(rgb)


TRACKER_PANELS = ("SP-TS positive", "SP-TS negative", "TDF + map points", "events kept / removed")
"""The Images tab's panels (tracking mode and the events-only view)."""
SLAM_PLACEHOLDER = "_SLAM mode shows here (Recording > viewer mode: slam)._"
IMAGES_IN_SLAM_MODE = "_SLAM mode: its images are in the **SLAM** tab (the tracker's time surfaces are not made)._"
SLAM_PANELS = ("tiny frame", "MCI + tracked features", "events (SLAM)")
"""Image panels of SLAM mode (the tracking panels' images do not exist there)."""


def _normalised_grey(img: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray:
    if img is None:
        return np.zeros((*shape, 3), np.uint8)
    a = np.asarray(img, np.float32)
    # Event images are counts with a few bright pixels: scale to the 99th percentile so edges stay visible.
    hi = float(np.percentile(a, 99.0)) if a.size else 1.0
    g = (np.clip(a / max(hi, 1e-12), 0.0, 1.0) * 255.0).astype(np.uint8)
    return np.repeat(g[..., None], 3, axis=2)


def mci_image(frame: Frame) -> np.ndarray:
    """The selected MCI in grey, tracked features drawn on it: green with a map point, yellow without; a red border on keyframes."""
    v = frame.slam
    shape = frame.ts_positive.shape
    rgb = upscale(_normalised_grey(v.mci, shape))
    s = _scale_for(shape[1])
    h, w = rgb.shape[:2]
    if v.features is not None and len(v.features):
        has = v.feature_has_point if v.feature_has_point is not None else np.zeros(len(v.features), bool)
        cols = np.where(has[:, None], [40, 230, 60], [250, 210, 0]).astype(np.uint8)
        px = np.round((v.features[:, 0] + 0.5) * s - 0.5).astype(np.int64)
        py = np.round((v.features[:, 1] + 0.5) * s - 0.5).astype(np.int64)
        r = max(2, s)
        for dy in range(-r + 1, r):
            for dx in range(-r + 1, r):
                x, y = px + dx, py + dy
                ok = (x >= 0) & (x < w) & (y >= 0) & (y < h)
                rgb[y[ok], x[ok]] = cols[ok]
    if v.keyframe:
        b = max(2, s)
        rgb[:b], rgb[-b:], rgb[:, :b], rgb[:, -b:] = (230, 40, 40), (230, 40, 40), (230, 40, 40), (230, 40, 40)
    return rgb


def slam_panel_images(frame: Frame) -> dict[str, np.ndarray]:
    """SLAM mode's panels: the last tiny frame, the selected MCI with tracked features, the step's events."""
    h, w = frame.ts_positive.shape
    return {
        "tiny frame": upscale(_normalised_grey(frame.slam.tiny_frame, (h, w))),
        "MCI + tracked features": mci_image(frame),
        "events (SLAM)": events_image(frame.events_kept, frame.events_removed, w, h),
    }


def panel_images(frame: Frame, colour_by: OverlayColour = OverlayColour.RESIDUAL) -> dict[str, np.ndarray]:
    """All panel images of a frame, by panel name (SLAM frames: :func:`slam_panel_images`)."""
    if frame.slam is not None:
        return slam_panel_images(frame)
    h, w = frame.ts_positive.shape
    return {
        "SP-TS positive": ts_image(frame.ts_positive, True),
        "SP-TS negative": ts_image(frame.ts_negative, False),
        "TDF + map points": tdf_image(frame, colour_by),
        "events kept / removed": events_image(frame.events_kept, frame.events_removed, w, h),
    }
