"""Event images: Gaussian splats of (optionally warped) events, their 8-bit form and the local-STD sharpness score.

Each event votes bilinearly at its (warped) position and the vote image is
blurred, which equals a Gaussian splat of the configured sigma. One kernel serves tiny frames (identity warp, paper eq. 2) and MCIs (eqs. 3/4):
each event carries a time-slice index and every slice has a 3x3 pixel homography
(Sim(2) warps and SE(3) warps with one scene depth are both homographies).
"""

from __future__ import annotations

import cv2
import numba as nb
import numpy as np


@nb.njit(cache=True)
def _bilinear_votes(x, y, w, slice_idx, H, width, height, scale):
    img = np.zeros((height, width), np.float32)
    # Sensor pixel centres map to scale * (u + 0.5) - 0.5 (``fine_coords``): the fine grid covers the same area.
    off = 0.5 * scale - 0.5
    for i in range(x.shape[0]):
        h = H[slice_idx[i]]
        xi = x[i]
        yi = y[i]
        zw = h[2, 0] * xi + h[2, 1] * yi + h[2, 2]
        if zw <= 1e-9:
            continue
        u = (h[0, 0] * xi + h[0, 1] * yi + h[0, 2]) / zw
        v = (h[1, 0] * xi + h[1, 1] * yi + h[1, 2]) / zw
        if scale != 1.0:
            u = scale * u + off
            v = scale * v + off
        if not (u > -1.0 and v > -1.0 and u < width and v < height):
            continue
        u0 = int(np.floor(u))
        v0 = int(np.floor(v))
        fu = u - u0
        fv = v - v0
        for dv in range(2):
            yy = v0 + dv
            if yy < 0 or yy >= height:
                continue
            wv = fv if dv else 1.0 - fv
            for du in range(2):
                xx = u0 + du
                if xx < 0 or xx >= width:
                    continue
                wu = fu if du else 1.0 - fu
                img[yy, xx] += w[i] * wu * wv
    return img


def event_image(
    x: np.ndarray,
    y: np.ndarray,
    p: np.ndarray | None,
    width: int,
    height: int,
    sigma: float = 1.0,
    slice_idx: np.ndarray | None = None,
    homographies: np.ndarray | None = None,
    scale: float = 1.0,
) -> np.ndarray:
    """Splat events (float pixel coordinates) into a float32 (H, W) image.

    ``p`` given -> signed polarity sum, else event counts. ``homographies`` (S, 3, 3)
    with ``slice_idx`` (N,) in ``[0, S)`` warp each event first; omitted -> no warp. ``scale`` > 1 renders on a grid
    ``scale`` times finer (``fine_shape`` pixels; positions by :func:`fine_coords`), ``sigma`` still in sensor pixels.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    y = np.ascontiguousarray(y, dtype=np.float64)
    w = np.ones(x.shape[0], np.float64) if p is None else np.ascontiguousarray(p, dtype=np.float64)
    if homographies is None:
        homographies = np.eye(3)[None]
        slice_idx = np.zeros(x.shape[0], np.int64)
    else:
        homographies = np.ascontiguousarray(homographies, dtype=np.float64).reshape(-1, 3, 3)
        slice_idx = np.ascontiguousarray(slice_idx, dtype=np.int64)
    fw, fh = fine_shape(width, height, scale)
    img = _bilinear_votes(x, y, w, slice_idx, homographies, fw, fh, float(scale))
    # Bilinear voting is a tent kernel of variance 1/6 per axis; blurring with the remaining
    # variance gives the paper's Gaussian splat (sigma_I) at a fraction of the per-event cost.
    sf = sigma * scale
    s = float(np.sqrt(max(sf * sf - 1.0 / 6.0, 1e-4)))
    k = 2 * int(np.ceil(3.0 * s)) + 1
    return cv2.GaussianBlur(img, (k, k), s, sigmaY=s, borderType=cv2.BORDER_CONSTANT)


def fine_shape(width: int, height: int, scale: float) -> tuple[int, int]:
    """(width, height) of the grid ``scale`` times finer than a ``width`` x ``height`` sensor, pixels."""
    return int(round(width * scale)), int(round(height * scale))


def fine_coords(uv: np.ndarray, scale: float) -> np.ndarray:
    """Sensor pixel positions (N, 2) on the grid ``scale`` times finer (pixel centres ``scale (u + 0.5) - 0.5``)."""
    return scale * (np.asarray(uv, np.float64) + 0.5) - 0.5


def sensor_coords(uv: np.ndarray, scale: float) -> np.ndarray:
    """Inverse of :func:`fine_coords`."""
    return (np.asarray(uv, np.float64) + 0.5) / scale - 0.5


def robust_maximum(magnitudes: np.ndarray) -> float | None:
    """The 99.5th percentile of the non-zero ``magnitudes`` (their maximum if that is 0), None if all are zero: the value
    an event image's 8-bit scaling maps to full contrast, so a few hot pixels do not darken the rest."""
    nz = magnitudes[magnitudes > 0]
    if nz.size == 0:
        return None
    top = float(np.percentile(nz, 99.5))
    return top if top > 0 else float(nz.max())


def to_uint8(img: np.ndarray) -> np.ndarray:
    """Scale an event image to 8 bits for FAST and KLT: robust maximum (99.5th percentile of non-zero pixels) -> 255.

    Signed images map 0 to 128 so both polarities keep contrast.
    """
    img = np.asarray(img, dtype=np.float32)
    signed = bool((img < 0).any())
    top = robust_maximum(np.abs(img))
    if top is None:
        return np.zeros(img.shape, np.uint8)
    if signed:
        out = 128.0 + 127.0 * np.clip(img / top, -1.0, 1.0)
    else:
        out = 255.0 * np.clip(img / top, 0.0, 1.0)
    return out.astype(np.uint8)


def local_std_score(img: np.ndarray, patch: int) -> float:
    """Mean over non-overlapping ``patch`` x ``patch`` blocks of the block's standard deviation (the paper's sharpness)."""
    img = np.asarray(img, dtype=np.float64)
    h = (img.shape[0] // patch) * patch
    w = (img.shape[1] // patch) * patch
    if h == 0 or w == 0:
        return float(img.std())
    blocks = img[:h, :w].reshape(h // patch, patch, w // patch, patch)
    return float(blocks.std(axis=(1, 3)).mean())
