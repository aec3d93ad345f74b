"""Event images: Gaussian splats of (optionally warped) events, their 8-bit form and the local-STD sharpness score.

Each event votes bilinearly at its (warped) position and the vote image is
blurred, which equals a Gaussian splat of the configured sigma. One kernel serves tiny frames (identity warp, paper eq. 2) and MCIs (eqs. 3/4):
each event carries a time-slice index and every slice has a 3x3 pixel homography
(Sim(2) warps and SE(3) warps with one scene depth are both homographies).

Session 26 (``/tmp/s26/speed26``), CPU: the sharpness score (:func:`local_std_score`, five per MCI), the 8-bit scaling
(:func:`to_uint8`, :func:`robust_maximum`) and the splat kernel run in numba with numpy's own arithmetic and summation
order, so every output is bit for bit the same (``tests/slam/test_event_image_kernels.py`` keeps the numpy code as the
reference; ``ident.py`` hashes the trajectories and every step's tracks, hypothesis, scores and MCI of landing
event-only seeds 0-3, event-inertial seed 0, indoor event-only seed 0 and E-I-C2 seed 1: identical to main). Per call on
the MCIs of a default landing run (``t_all.py`` on ``rec_args.py``'s recorded calls, thread CPU, loaded machine):
score 0.36 -> 0.10-0.15 ms, 8-bit scaling 0.4-0.5 -> 0.10-0.23 ms (numba's ``np.partition`` took 20-830 us for the
percentile, a heap of the top 0.5 % 8-58 us), splat votes about a third less (no array view per event). With
:mod:`evpose.slam.mci`'s and :mod:`evpose.slam.parallax_warp`'s kernels, the main thread's CPU per MCI: module notes of
:mod:`evpose.slam.mci`.
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
        s = slice_idx[i]  # indexed in place: a view of H[s] per event cost a third of the kernel (session 26)
        xi = x[i]
        yi = y[i]
        zw = H[s, 2, 0] * xi + H[s, 2, 1] * yi + H[s, 2, 2]
        if zw <= 1e-9:
            continue
        u = (H[s, 0, 0] * xi + H[s, 0, 1] * yi + H[s, 0, 2]) / zw
        v = (H[s, 1, 0] * xi + H[s, 1, 1] * yi + H[s, 1, 2]) / zw
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


@nb.njit(cache=True)
def _nonzero_magnitudes(img, stride):
    """``|img|`` where it is above 0 at every ``stride``-th row and column, in raster order (NaN left out, as by
    ``m[m > 0]``); whether any of those pixels is negative; whether all are finite."""
    h, w = img.shape
    out = np.empty(((h + stride - 1) // stride) * ((w + stride - 1) // stride), img.dtype)
    n = 0
    neg = False
    finite = True
    for i in range(0, h, stride):
        for j in range(0, w, stride):
            v = img[i, j]
            if not np.isfinite(v):
                finite = False
            if v < 0:
                neg = True
                v = -v
            if v > 0:
                out[n] = v
                n += 1
    return out[:n], neg, finite


@nb.njit(cache=True)
def _sift_down(heap, i, m):
    while True:
        c = 2 * i + 1
        if c >= m:
            return
        if c + 1 < m and heap[c + 1] < heap[c]:
            c += 1
        if heap[c] >= heap[i]:
            return
        heap[i], heap[c] = heap[c], heap[i]
        i = c


@nb.njit(cache=True)
def _order_statistics(values, k):
    """The ``k``-th and ``k + 1``-th smallest of ``values`` (0-based; the second only when it exists, else the first),
    from a min-heap of the ``n - k`` largest: a high percentile reads a small heap, and numba's ``np.partition`` took
    20-830 us on the same MCIs."""
    n = values.shape[0]
    m = n - k
    heap = values[:m].copy()
    for i in range(m // 2 - 1, -1, -1):
        _sift_down(heap, i, m)
    for i in range(m, n):
        if values[i] > heap[0]:
            heap[0] = values[i]
            _sift_down(heap, 0, m)
    a = heap[0]
    if m < 2:
        return a, a
    if m == 2:
        return a, heap[1]
    return a, min(heap[1], heap[2])


def _percentile_995(nz: np.ndarray) -> float:
    """``np.percentile(nz, 99.5)`` (linear, numpy 2's arithmetic in ``nz``'s dtype) bit for bit, for ``nz`` 1-D with no
    NaN: the two order statistics (:func:`_order_statistics`) and numpy's ``_lerp``."""
    n = nz.shape[0]
    v = (n - 1) * (99.5 / 100)
    prev = int(np.floor(v))
    if v >= n - 1:  # numpy takes the last element for both
        prev = -1
    gamma = v - prev
    a, b = _order_statistics(nz, prev if prev >= 0 else n - 1)
    if prev < 0:
        b = a
    typ = nz.dtype.type
    d = typ(b - a)
    if gamma >= 0.5:
        return float(typ(b - d * typ(1 - gamma)))
    return float(typ(a + d * typ(gamma)))


def robust_maximum(magnitudes: np.ndarray, stride: int = 1) -> float | None:
    """The 99.5th percentile of the non-zero ``magnitudes`` (their maximum if that is 0), None if all are zero: the value
    an event image's 8-bit scaling maps to full contrast, so a few hot pixels do not darken the rest. Negative values
    count by their magnitude; ``stride`` > 1 reads every ``stride``-th row and column of a 2-D array only. Session 26:
    bit for bit ``np.percentile(m[m > 0], 99.5)`` of ``m = |magnitudes[::stride, ::stride]|`` (the reference in
    ``tests/slam/test_event_image_kernels.py``) with the order statistics in numba and no mask or copy of the image."""
    m = np.asarray(magnitudes)
    if m.dtype not in (np.float32, np.float64):  # numpy's own arithmetic for other types
        m = np.abs(m[::stride, ::stride] if stride > 1 else m)
        nz = m[m > 0]
        if nz.size == 0:
            return None
        top = float(np.percentile(nz, 99.5))
        return top if top > 0 else float(nz.max())
    nz, _, _ = _nonzero_magnitudes(m if m.ndim == 2 else m.reshape(1, -1), int(stride))
    if nz.size == 0:
        return None
    top = _percentile_995(nz)
    return top if top > 0 else float(nz.max())


@nb.njit(cache=True)
def _scale_uint8(img, top, signed):
    """numpy's ``(255 * clip(img / top, 0, 1)).astype(uint8)`` (``signed``: ``128 + 127 * clip(img / top, -1, 1)``) in
    ``img``'s float32 arithmetic."""
    h, w = img.shape
    out = np.empty((h, w), np.uint8)
    t = np.float32(top)
    lo = np.float32(-1.0) if signed else np.float32(0.0)
    one = np.float32(1.0)
    for i in range(h):
        for j in range(w):
            x = img[i, j] / t
            x = lo if x < lo else (one if x > one else x)
            if signed:
                out[i, j] = np.uint8(np.float32(128.0) + np.float32(127.0) * x)
            else:
                out[i, j] = np.uint8(np.float32(255.0) * x)
    return out


def to_uint8(img: np.ndarray) -> np.ndarray:
    """Scale an event image to 8 bits for FAST and KLT: robust maximum (99.5th percentile of non-zero pixels) -> 255.

    Signed images map 0 to 128 so both polarities keep contrast. Session 26: the numpy form (abs, mask, percentile,
    clip; ``tests/slam/test_event_image_kernels.py`` keeps it as the reference) in two numba passes, bit for bit; an
    image with NaN takes the numpy form (its NaN pixels' 8-bit value is numpy's cast).
    """
    img = np.asarray(img, dtype=np.float32)
    if img.ndim != 2:
        return _to_uint8_numpy(img)
    nz, signed, finite = _nonzero_magnitudes(img, 1)
    if not finite:
        return _to_uint8_numpy(img)
    if nz.size == 0:
        return np.zeros(img.shape, np.uint8)
    top = _percentile_995(nz)
    return _scale_uint8(img, top if top > 0 else float(nz.max()), signed)


def _to_uint8_numpy(img: np.ndarray) -> np.ndarray:
    signed = bool((img < 0).any())
    top = robust_maximum(np.abs(img))
    if top is None:
        return np.zeros(img.shape, np.uint8)
    if signed:
        out = 128.0 + 127.0 * np.clip(img / top, -1.0, 1.0)
    else:
        out = 255.0 * np.clip(img / top, 0.0, 1.0)
    return out.astype(np.uint8)


@nb.njit(cache=True)
def _pairwise_sum(buf, n):
    """numpy's pairwise summation of ``n`` <= 128 float64 (``loops_utils.h``: under 8 one by one from 0, else 8
    running sums combined as ((0+1)+(2+3))+((4+5)+(6+7)), then the rest one by one)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += buf[i]
        return res
    r0, r1, r2, r3 = buf[0], buf[1], buf[2], buf[3]
    r4, r5, r6, r7 = buf[4], buf[5], buf[6], buf[7]
    i = 8
    while i < n - (n % 8):
        r0 += buf[i]
        r1 += buf[i + 1]
        r2 += buf[i + 2]
        r3 += buf[i + 3]
        r4 += buf[i + 4]
        r5 += buf[i + 5]
        r6 += buf[i + 6]
        r7 += buf[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += buf[i]
        i += 1
    return res


@nb.njit(cache=True)
def _block_stds(img, patch):
    """Standard deviation of each ``patch`` x ``patch`` block, float64, summed in numpy's order for
    ``img.reshape(H, patch, W, patch).std(axis=(1, 3))`` with W >= 2: block rows one after another, each row pairwise."""
    nb_r = img.shape[0] // patch
    nb_c = img.shape[1] // patch
    out = np.empty((nb_r, nb_c))
    buf = np.empty(patch)
    n = float(patch * patch)
    for bi in range(nb_r):
        for bj in range(nb_c):
            s = 0.0
            for r in range(patch):
                for c in range(patch):
                    buf[c] = np.float64(img[bi * patch + r, bj * patch + c])
                s += _pairwise_sum(buf, patch)
            mean = s / n
            q = 0.0
            for r in range(patch):
                for c in range(patch):
                    d = np.float64(img[bi * patch + r, bj * patch + c]) - mean
                    buf[c] = d * d
                q += _pairwise_sum(buf, patch)
            out[bi, bj] = np.sqrt(q / n)
    return out


def local_std_score(img: np.ndarray, patch: int) -> float:
    """Mean over non-overlapping ``patch`` x ``patch`` blocks of the block's standard deviation (the paper's sharpness).

    Session 26: the blocks' deviations in numba, bit for bit numpy's ``blocks.std(axis=(1, 3))`` of the float64 image
    (the reference in ``tests/slam/test_event_image_kernels.py``; 0.36 -> 0.10 ms on a 346x260 MCI, five per MCI).
    numpy sums a single column of blocks in another order, so that case (and patches over 128 px) stays numpy's.
    """
    img = np.asarray(img)
    h = (img.shape[0] // patch) * patch
    w = (img.shape[1] // patch) * patch
    if h == 0 or w == 0:
        return float(np.asarray(img, dtype=np.float64).std())
    if img.dtype not in (np.float32, np.float64) or w < 2 * patch or patch > 128:
        img = np.asarray(img, dtype=np.float64)
        blocks = img[:h, :w].reshape(h // patch, patch, w // patch, patch)
        return float(blocks.std(axis=(1, 3)).mean())
    return float(_block_stds(img, int(patch)).mean())
