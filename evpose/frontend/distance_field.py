"""Temporal distance field (TDF = 1 - TS) with gradients, sampled at query points by bilinear interpolation.

EV-Pose section IV-B. The field is ~0 on the newest edge position and rises
behind and ahead of a moving edge. Peers blur it to widen the basin of
convergence (ESVO 5x5, Canny-EVT 7x7), so the blur size is a parameter.
Registration samples value and gradient at a few thousand projected points per
iteration; the field is therefore built once per step (optionally only inside a
region of interest around the projected map) and then sampled, never rebuilt
per iteration.

Field slots: 0 = combined polarity, 1 = ON (+1), 2 = OFF (-1); a per-point
polarity array selects the slot (see :func:`polarity_slots`).

Not kept (session 12): :func:`bilinear_sample` reading the three fields through flat views at one unsigned offset
(what sped up the polarity filter's kernels) made registration's ``_linearise_at``, which inlines it, slower: 210 ->
266-274 us per call on 80 of the demo's linearisations after 48 MB of other traffic (same outputs).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numba as nb
import numpy as np

from evpose.frontend.time_surface import SeparatedTimeSurface

SLOT_OF_POLARITY = {0: 0, 1: 1, -1: 2}
_POLARITY_OF_SLOT = {0: 0, 1: 1, 2: -1}


@dataclass
class DistanceFieldConfig:
    """TDF settings."""

    blur_px: int = field(default=3, metadata={"min": 0, "max": 15, "step": 2, "unit": "px"})
    """Gaussian blur kernel size in pixels (odd; 0 or 1 = no blur). Wider kernels widen the basin and add lag.

    The field is one-sided (a slow ramp behind a moving edge, a step ahead of it), so
    a blur moves its minimum back along the motion: by 0.3-1 px for 3-5 px kernels
    at 1-4 px of motion per ``eta``; and it flattens thin (slow-edge) minima, so
    with 5 px half the true edge points of the simulated landing read TDF > 0.7. Session 7, ``stpe`` at 240x180
    (seeds 0-3, mean ATE), where a pixel is 1.44x wider than at 346x260: 1 / 3 / 5 px gave 39.65 / 23.80 / 27.81 mm
    (true-edge map: 19.40 / 16.83 / - mm). Session 16, ``full`` (3 px: 6.38 / 5.91 mm at 346x260 seeds 0-3 / 4-7,
    7.25 at 240x180 seeds 0-3): 1 px 6.86 mm (seeds 0-3), 5 px 6.30 / 5.86 / 7.33 mm, 7 px 6.23 mm (seeds 0-3, ARE
    0.075 against 0.066 deg): within the seeds' spread, not changed."""
    coarse_blur_px: int = field(default=0, metadata={"min": 0, "max": 41, "step": 2, "unit": "px", "zero": "off"})
    """Blur of an extra, coarser field registered first to widen the basin of convergence (0 = single level), pixels
    (odd; the viewer offers 1, 3, ... 41 and the 0 as a checkbox, ``zero``).

    Session 11, ``stpe`` at 240x180, seeds 0-3 (16.80 mm single level, before ``edge_offsets``): 7 / 11 px gave
    18.10 / 18.13 mm: tracking from the truth needs no wider basin, and the coarse level's pose is a worse start.
    Session 15, ``stpe`` seeds 0-3, 7 px: 2 s landing 12.40 / 13.80 -> 13.04 / 15.15 mm at 346x260 / 240x180; the 3 s
    landing 120.07 -> 98.20 mm ATE (lost poses left out), but its RMS error of every pose over 0-0.5 / 0.5-1 / 1-1.5 /
    1.5-2 s 61.1 / 46.9 / 69.0 / 365.3 -> 61.9 / 43.3 / 62.9 / 370.7 mm: the turn is lost all the same.
    Session 15, ``full`` at 346x260 (seeds 0-3, 6.38 mm), to move the fine level off the prediction it echoes: 7 / 11
    px gave 6.53 / 6.56 mm."""

    def level(self, blur_px: int) -> "DistanceFieldConfig":
        """This config with another blur (one level of a coarse-to-fine pyramid)."""
        return DistanceFieldConfig(blur_px=int(blur_px), coarse_blur_px=0)


def polarity_slots(polarity: np.ndarray | None, n: int) -> np.ndarray:
    """Per-point field slot (int8): +1 -> ON field, -1 -> OFF field, 0 or None -> combined field."""
    if polarity is None:
        return np.zeros(n, dtype=np.int8)
    p = np.asarray(polarity).astype(np.int8, copy=False)
    return np.where(p > 0, 1, np.where(p < 0, 2, 0)).astype(np.int8)


LUT_BINS_PER_ETA = 512
"""Resolution of the decay lookup table: ``eta / 512`` per bin, so the TDF is off by < 0.001 (bins round)."""
LUT_SPAN_ETA = 12
"""The table covers ``12 eta``; older (and never-fired) pixels read exactly 1."""


def decay_lut(eta_us: float) -> tuple[np.ndarray, int]:
    """(table, shift): ``table[(dt + half) >> shift] = 1 - exp(-dt / eta)`` for dt in microseconds, last entry 1.

    A power-of-two bin turns the per-pixel exp into a shift and a load: 10x faster
    than evaluating exp per pixel on this machine, for < 0.001 error.
    """
    shift = max(int(np.floor(np.log2(max(eta_us / LUT_BINS_PER_ETA, 1.0)))), 0)
    n = int(np.ceil(LUT_SPAN_ETA * eta_us / (1 << shift))) + 2
    dt = np.arange(n, dtype=np.float64) * (1 << shift)
    table = (1.0 - np.exp(-dt / eta_us)).astype(np.float32)
    table[-1] = 1.0
    return table, shift


@nb.njit(cache=True)
def _tdf_kernel(last, t_us, lut, shift, r0, c0, out):
    """TDF of the box starting at (r0, c0) with the shape of ``out`` from a last-timestamp map."""
    h, w = out.shape
    n = lut.shape[0]
    half = np.int64(1) << max(shift - 1, 0) if shift > 0 else np.int64(0)
    # Pixels last fired at or before ``oldest`` fall in the table's last bin (exactly what the lookup would
    # read): most pixels of a frame (80 % on the simulated landing), which then skip the lookup, 1.6x faster.
    oldest = t_us - ((np.int64(n - 1) << shift) - half)
    top = lut[n - 1]
    for r in range(h):
        # Row views: one bounds/stride computation per row instead of per pixel.
        src = last[r0 + r, c0:c0 + w]
        dst = out[r]
        for c in range(w):
            s = src[c]
            if s <= oldest:
                dst[c] = top
                continue
            d = t_us - s
            if d < 0:
                d = 0
            dst[c] = lut[(d + half) >> shift]


@nb.njit(cache=True)
def field_derivatives(img, r0, c0, curvature, gu, gv, huu, huv, hvv):
    """Central first differences and (if ``curvature``) second differences of ``img`` (the box) in one pass,
    written at offset (r0, c0); borders replicate, as OpenCV's BORDER_REPLICATE.

    Row views and a branch-free interior loop (border columns done apart) let LLVM vectorise:
    4-5x faster than clamping every index, same arithmetic in the same order (bit-identical).
    Needs a box of at least 2 x 2 (``compute`` guarantees it).
    """
    h, w = img.shape
    for r in range(h):
        up = img[r - 1 if r > 0 else 0]
        mid = img[r]
        dn = img[r + 1 if r < h - 1 else h - 1]
        ogu = gu[r0 + r, c0:c0 + w]
        ogv = gv[r0 + r, c0:c0 + w]
        if curvature:
            # All five outputs in one sweep of the three rows: 12 % faster than a sweep for the gradients
            # and another for the curvature (the rows are read once).
            ouu = huu[r0 + r, c0:c0 + w]
            ovv = hvv[r0 + r, c0:c0 + w]
            ouv = huv[r0 + r, c0:c0 + w]
            for c in range(1, w - 1):
                f0 = mid[c]
                ogu[c] = 0.5 * (mid[c + 1] - mid[c - 1])
                ogv[c] = 0.5 * (dn[c] - up[c])
                ouu[c] = mid[c + 1] - 2.0 * f0 + mid[c - 1]
                ovv[c] = dn[c] - 2.0 * f0 + up[c]
                ouv[c] = 0.25 * (dn[c + 1] - dn[c - 1] - up[c + 1] + up[c - 1])
            for c in (0, w - 1):
                ca = c - 1 if c > 0 else 0
                cb = c + 1 if c < w - 1 else w - 1
                f0 = mid[c]
                ogu[c] = 0.5 * (mid[cb] - mid[ca])
                ogv[c] = 0.5 * (dn[c] - up[c])
                ouu[c] = mid[cb] - 2.0 * f0 + mid[ca]
                ovv[c] = dn[c] - 2.0 * f0 + up[c]
                ouv[c] = 0.25 * (dn[cb] - dn[ca] - up[cb] + up[ca])
        else:
            for c in range(1, w - 1):
                ogu[c] = 0.5 * (mid[c + 1] - mid[c - 1])
                ogv[c] = 0.5 * (dn[c] - up[c])
            for c in (0, w - 1):
                ogu[c] = 0.5 * (mid[c + 1 if c < w - 1 else w - 1] - mid[c - 1 if c > 0 else 0])
                ogv[c] = 0.5 * (dn[c] - up[c])


@nb.njit(cache=True, inline="always")
def _bilinear_weights(u, v, r1, c1):
    """(x0, y0, w00, w01, w10, w11): top-left pixel of the 2x2 cell holding (u, v), clamped into a box ending at
    row ``r1`` / column ``c1``, and the bilinear weights of its four pixels."""
    x0 = int(u)
    y0 = int(v)
    if x0 > c1 - 2:
        x0 = c1 - 2
    if y0 > r1 - 2:
        y0 = r1 - 2
    a = u - x0
    b = v - y0
    return x0, y0, (1.0 - a) * (1.0 - b), a * (1.0 - b), (1.0 - a) * b, a * b


@nb.njit(cache=True, inline="always")
def bilinear_sample(value, gx, gy, box, slot, u, v):
    """(tdf, dtdf/du, dtdf/dv, inside) at sub-pixel (u=column, v=row) of ``slot``.

    Only the computed ``box`` = (row0, row1, col0, col1) holds the field (the rest of
    the arrays is stale, to save clearing them); outside it -> (1, 0, 0, False).
    """
    r0 = box[0]
    r1 = box[1]
    c0 = box[2]
    c1 = box[3]
    if not (u >= c0 and v >= r0 and u <= c1 - 1.0 and v <= r1 - 1.0) or r1 - r0 < 2 or c1 - c0 < 2:
        return 1.0, 0.0, 0.0, False
    x0, y0, w00, w01, w10, w11 = _bilinear_weights(u, v, r1, c1)
    f = w00 * value[slot, y0, x0] + w01 * value[slot, y0, x0 + 1] + w10 * value[slot, y0 + 1, x0] + w11 * value[slot, y0 + 1, x0 + 1]
    fx = w00 * gx[slot, y0, x0] + w01 * gx[slot, y0, x0 + 1] + w10 * gx[slot, y0 + 1, x0] + w11 * gx[slot, y0 + 1, x0 + 1]
    fy = w00 * gy[slot, y0, x0] + w01 * gy[slot, y0, x0 + 1] + w10 * gy[slot, y0 + 1, x0] + w11 * gy[slot, y0 + 1, x0 + 1]
    return f, fx, fy, True


@nb.njit(cache=True, inline="always")
def bilinear_sample_curvature(hess, box, slot, u, v):
    """(d2/du2, d2/dudv, d2/dv2) of ``slot`` at a sub-pixel point already known to be inside ``box``."""
    x0, y0, w00, w01, w10, w11 = _bilinear_weights(u, v, box[1], box[3])
    out0 = w00 * hess[0, slot, y0, x0] + w01 * hess[0, slot, y0, x0 + 1] + w10 * hess[0, slot, y0 + 1, x0] + w11 * hess[0, slot, y0 + 1, x0 + 1]
    out1 = w00 * hess[1, slot, y0, x0] + w01 * hess[1, slot, y0, x0 + 1] + w10 * hess[1, slot, y0 + 1, x0] + w11 * hess[1, slot, y0 + 1, x0 + 1]
    out2 = w00 * hess[2, slot, y0, x0] + w01 * hess[2, slot, y0, x0 + 1] + w10 * hess[2, slot, y0 + 1, x0] + w11 * hess[2, slot, y0 + 1, x0 + 1]
    return out0, out1, out2


@nb.njit(cache=True, inline="always")
def _second_differences(img, r0, r1, c0, c1, y, x):
    """(d2/du2, d2/dudv, d2/dv2) at pixel (y, x) of one slot's field, borders of the box replicated: the same
    float32 values :func:`field_derivatives` writes into ``hess`` (same expressions, same rounding)."""
    ya = y - 1 if y > r0 else r0
    yb = y + 1 if y < r1 - 1 else r1 - 1
    xa = x - 1 if x > c0 else c0
    xb = x + 1 if x < c1 - 1 else c1 - 1
    f0 = img[y, x]
    uu = np.float32(img[y, xb] - 2.0 * f0 + img[y, xa])
    vv = np.float32(img[yb, x] - 2.0 * f0 + img[ya, x])
    uv = np.float32(0.25 * (img[yb, xb] - img[yb, xa] - img[ya, xb] + img[ya, xa]))
    return uu, uv, vv


@nb.njit(cache=True, inline="always")
def bilinear_curvature_from_value(value, box, slot, u, v):
    """:func:`bilinear_sample_curvature` computed from the field itself at the four pixels around (u, v), bit for
    bit, so ``compute`` need not fill :attr:`TemporalDistanceField.hess`: registration reads a few thousand points
    per update, the curvature images cost 50 us per update at 346x260. Point already known inside ``box``."""
    r0 = box[0]
    r1 = box[1]
    c0 = box[2]
    c1 = box[3]
    x0, y0, w00, w01, w10, w11 = _bilinear_weights(u, v, r1, c1)
    img = value[slot]
    p00 = _second_differences(img, r0, r1, c0, c1, y0, x0)
    p01 = _second_differences(img, r0, r1, c0, c1, y0, x0 + 1)
    p10 = _second_differences(img, r0, r1, c0, c1, y0 + 1, x0)
    p11 = _second_differences(img, r0, r1, c0, c1, y0 + 1, x0 + 1)
    out0 = w00 * p00[0] + w01 * p01[0] + w10 * p10[0] + w11 * p11[0]
    out1 = w00 * p00[1] + w01 * p01[1] + w10 * p10[1] + w11 * p11[1]
    out2 = w00 * p00[2] + w01 * p01[2] + w10 * p10[2] + w11 * p11[2]
    return out0, out1, out2


@nb.njit(cache=True)
def _sample_many(value, gx, gy, box, slots, uv, out_val, out_grad, out_inside):
    for i in range(uv.shape[0]):
        f, fx, fy, ok = bilinear_sample(value, gx, gy, box, np.int64(slots[i]), uv[i, 0], uv[i, 1])
        out_val[i] = f
        out_grad[i, 0] = fx
        out_grad[i, 1] = fy
        out_inside[i] = ok


class TemporalDistanceField:
    """TDF images per polarity slot plus their gradients, built from an SP-TS at a query time."""

    def __init__(self, config: DistanceFieldConfig, width: int, height: int):
        self.config = config
        self.width = int(width)
        self.height = int(height)
        shape = (3, self.height, self.width)
        self.value = np.ones(shape, dtype=np.float32)
        """float32 (3, H, W): TDF per slot (0 combined, 1 ON, 2 OFF); only valid inside :attr:`box` (use :meth:`image`)."""
        self.grad_u = np.zeros(shape, dtype=np.float32)
        """float32 (3, H, W): d TDF / d column, per pixel."""
        self.grad_v = np.zeros(shape, dtype=np.float32)
        """float32 (3, H, W): d TDF / d row, per pixel."""
        self.hess = np.zeros((3,) + shape, dtype=np.float32)
        """float32 (3, 3, H, W): second derivatives (d2/du2, d2/dudv, d2/dv2) per slot, per pixel^2."""
        self.t_us: int | None = None
        self.slots_ready: tuple[int, ...] = ()
        """Slots the last :meth:`compute` filled."""
        self.box = np.zeros(4, dtype=np.int64)
        """(row0, row1, col0, col1) where the last :meth:`compute` wrote the field; outside it the field is 1."""
        self._lut: np.ndarray | None = None
        self._lut_shift = 0
        self._lut_eta = -1.0
        self._scratch: np.ndarray | None = None
        """float32 (2, H * W): the TDF of the box and its blur (when not written into :attr:`value` directly), reused."""

    def compute(self, surface: SeparatedTimeSurface, t_us: int, polarities=(0,), roi: tuple[int, int, int, int] | None = None, curvature: bool = True) -> None:
        """Build the field at ``t_us`` for the given polarities (+1, -1, 0) inside ``roi`` = (row0, row1, col0, col1).

        Outside the box the field reads 1 with zero gradient (no evidence there); the
        arrays are not cleared there, samplers check :attr:`box` instead.
        ``curvature`` also fills :attr:`hess` (for inspection: registration derives the same values from
        :attr:`value` at its points with :func:`bilinear_curvature_from_value`).
        Blur and gradients run on the box with replicated borders, so a box padded
        by the blur radius gives the full image's values inside it.
        """
        if roi is None:
            r0, r1, c0, c1 = 0, self.height, 0, self.width
        else:
            r0, r1, c0, c1 = (int(v) for v in roi)
            r0, c0 = max(r0, 0), max(c0, 0)
            r1, c1 = min(r1, self.height), min(c1, self.width)
        eta_us = float(surface.config.eta_ms) * 1e3
        if self._lut is None or self._lut_eta != eta_us:
            self._lut, self._lut_shift = decay_lut(eta_us)
            self._lut_eta = eta_us
        slots = sorted({SLOT_OF_POLARITY[int(p)] for p in polarities})
        self.t_us = int(t_us)
        if r1 - r0 < 2 or c1 - c0 < 2:
            self.slots_ready = ()
            self.box[:] = 0
            return
        k = int(self.config.blur_px)
        if k >= 2 and k % 2 == 0:
            k += 1
        # The box changes every update: views of two whole-image scratch rows (the TDF, and the blur of a box that is
        # not full-width), not a new TDF and a new blurred image (~0.35 MB each at 346x260) per update and slot.
        if self._scratch is None:
            self._scratch = np.empty((2, self.height * self.width), dtype=np.float32)
        shape, size = (r1 - r0, c1 - c0), (r1 - r0) * (c1 - c0)
        buf = self._scratch[0, :size].reshape(shape)
        for s in slots:
            _tdf_kernel(surface.last_of(_POLARITY_OF_SLOT[s]), np.int64(t_us), self._lut, self._lut_shift, r0, c0, buf)
            target = self.value[s, r0:r1, c0:c1]
            if k >= 3 and target.flags.c_contiguous:
                # Blur straight into the field (a full-width box is contiguous): no new image, no copy.
                img = cv2.GaussianBlur(buf, (k, k), 0, dst=target, borderType=cv2.BORDER_REPLICATE)
                if not np.shares_memory(img, self.value):
                    target[...] = img
            else:
                img = cv2.GaussianBlur(buf, (k, k), 0, dst=self._scratch[1, :size].reshape(shape),
                                       borderType=cv2.BORDER_REPLICATE) if k >= 3 else buf
                target[...] = img
            # Central differences (pixels^-1) and, for Newton steps, second differences (pixels^-2).
            field_derivatives(img, r0, c0, bool(curvature), self.grad_u[s], self.grad_v[s], self.hess[0, s], self.hess[1, s], self.hess[2, s])
        self.slots_ready = tuple(slots)
        self.box[:] = (r0, r1, c0, c1)

    def sample(self, uv: np.ndarray, polarity: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values (N,), gradients (N, 2) (d/du, d/dv) and inside-mask (N,) at sub-pixel points ``uv`` (N, 2)."""
        uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
        n = uv.shape[0]
        val = np.empty(n)
        grad = np.empty((n, 2))
        inside = np.empty(n, dtype=np.bool_)
        _sample_many(self.value, self.grad_u, self.grad_v, self.box, polarity_slots(polarity, n), uv, val, grad, inside)
        return val, grad, inside

    def image(self, polarity: int = 0) -> np.ndarray:
        """The field of one polarity (+1, -1, 0) as float32 (H, W), 1 outside the computed box and for slots not computed."""
        out = np.ones((self.height, self.width), dtype=np.float32)
        slot = SLOT_OF_POLARITY[int(polarity)]
        if slot in self.slots_ready:
            r0, r1, c0, c1 = (int(v) for v in self.box)
            out[r0:r1, c0:c1] = self.value[slot, r0:r1, c0:c1]
        return out
