"""The distance field of ``T_align`` built from its patch pixels, not from a composed image.

:class:`~evpose.frontend.distance_field.TemporalDistanceField.compute` reads a
last-timestamp image over the whole box. ``T_align`` shows events only at its
patch pixels (about 15,000 of the 90,000 at 346x260 in ``full``): everywhere
else it reads "never fired", i.e. TDF 1. So the field's box is filled with that
value and only the patch pixels are looked up, from the compact (pixel,
timestamp) list :meth:`AlignedTimeSurface.compose` keeps; no int64 image is
written, reset and scanned per step. Blur and derivatives then run on the box
as ``compute`` runs them, so the field is bit for bit the one ``compute`` builds
from :meth:`AlignedTimeSurface.last_of` (tested).

With the tracker's settings (3 px blur, no curvature) one compiled pass does the blur and the gradients
(:func:`_blur3_field`), row by row into the field, from a persistent whole-image TDF scratch that only the patch pixels
ever leave (:func:`_scatter_tdf` puts the last step's back): no box-sized fill, no separate blur output read again
by the derivatives. The blur is OpenCV's 3 x 3 Gaussian on float32 (the kernel 1/4, 1/2, 1/4, rows then columns,
``(left + right) / 4 + centre / 2``, replicated borders), bit for bit (tested against ``cv2.GaussianBlur``; the
``(left + right)`` grouping matters: ``left / 4 + centre / 2 + right / 4`` differs in the last bit at ~12 % of the
pixels). Session 19, a whole 346x260 box of a random TDF, hot: blur and gradients 62-69 us against 128-150 us for
``cv2.GaussianBlur`` and :func:`~evpose.frontend.distance_field.field_derivatives` (load ~3). A first version that
picked its three rows by ``row % 3`` from one (3, w) array did not vectorise: 198 us, slower than the cv2 path.
Not kept (in-process A/B, ``full`` 346x260 seed 0, 4 rounds, same poses): the TDF scattered into the scratch by
``T_align``'s time-selecting pass instead of a second pass over the patch list here, CPU per update -0.010 / +0.023 /
+0.026 / +0.011 ms median paired: the cost is the scratch's cache lines, not the list.
Not kept either (session 21, ``stpe+filter`` 346x260 seed 0, bit for bit the same field): the blur and gradients only
in the 8 px tiles within two pixels of a TDF pixel that is not the table's last bin (median 5,174 such pixels in a
89,960-pixel box; 367 of 1,452 tiles, 25 % of the box), the slot images kept at the empty field's values everywhere
else (``top``, no gradient) and the last step's tiles put back. Hot on one step's inputs: 56 us against 42-44 us for
the whole box in :func:`_blur3_field` (a run of tiles gives short rows, whose loops do not pay for vectorising; a first
version with clamped indices in the inner loops did not vectorise at all: 440 us for the whole box), and marking the
tiles in :func:`_scatter_tdf` added ~46 us in a run: the field went from 0.155 to 0.227 ms per update.
"""

from __future__ import annotations

import cv2
import numba as nb
import numpy as np

from evpose.frontend.distance_field import TemporalDistanceField, field_derivatives, decay_lut
from evpose.fusion.aligned_surface import AlignedTimeSurface


@nb.njit(cache=True, inline="always")
def _lut_span(lut, shift, t_us):
    """(half, oldest, top) of the decay table at ``t_us``: the rounding half-bin, the newest timestamp that reads the
    table's last bin (``top``) as ``_tdf_kernel`` bins them."""
    n_lut = lut.shape[0]
    half = np.int64(1) << max(shift - 1, 0) if shift > 0 else np.int64(0)
    return half, t_us - ((np.int64(n_lut - 1) << shift) - half), lut[n_lut - 1]


@nb.njit(cache=True, inline="always")
def _lut_value(lut, shift, half, t_us, s):
    """The table's value for a pixel last fired at ``s`` (a timestamp newer than the span's ``oldest``)."""
    d = t_us - s
    if d < 0:
        d = 0
    return lut[(d + half) >> shift]


@nb.njit(cache=True)
def _sparse_tdf(touched, times, n, t_us, lut, shift, r0, r1, c0, c1, out):
    """TDF of the box (r0:r1, c0:c1) into ``out`` (its shape): the table's last bin (never fired or older than it)
    everywhere but at the listed pixels, whose timestamps are looked up exactly as ``_tdf_kernel`` does."""
    half, oldest, top = _lut_span(lut, shift, t_us)
    out[:, :] = top
    for i in range(n):
        r = touched[i, 0]
        c = touched[i, 1]
        if r < r0 or r >= r1 or c < c0 or c >= c1:
            continue
        s = times[i]
        if s <= oldest:
            continue  # already ``top``
        out[r - r0, c - c0] = _lut_value(lut, shift, half, t_us, s)


@nb.njit(cache=True)
def _scatter_tdf(touched, times, n, t_us, lut, shift, r0, r1, c0, c1, buf, written, n_written):
    """:func:`_sparse_tdf` into the whole-image ``buf`` that reads the table's last bin everywhere but at the flat
    pixel offsets ``written[:n_written]`` (the last call's): those are put back first, then this call's pixels other
    than the last bin are written and listed in ``written``; returns how many."""
    half, oldest, top = _lut_span(lut, shift, t_us)
    flat = buf.reshape(-1)
    width = buf.shape[1]
    for i in range(n_written):
        flat[written[i]] = top
    m = 0
    for i in range(n):
        r = touched[i, 0]
        c = touched[i, 1]
        if r < r0 or r >= r1 or c < c0 or c >= c1:
            continue
        s = times[i]
        if s <= oldest:
            continue
        p = r * width + c
        flat[p] = _lut_value(lut, shift, half, t_us, s)
        written[m] = p
        m += 1
    return m


@nb.njit(cache=True)
def _blur3_row(src, out, w):
    """OpenCV's horizontal pass of the 3 x 3 Gaussian (float32, replicated borders) of the row ``src`` (``w`` >= 2)."""
    k0 = np.float32(0.25)
    k1 = np.float32(0.5)
    out[0] = (src[0] + src[1]) * k0 + src[0] * k1
    for c in range(1, w - 1):
        out[c] = (src[c - 1] + src[c + 1]) * k0 + src[c] * k1
    out[w - 1] = (src[w - 2] + src[w - 1]) * k0 + src[w - 1] * k1


@nb.njit(cache=True)
def _gradient_row(up, mid, dn, ogu, ogv, w):
    """:func:`~evpose.frontend.distance_field.field_derivatives` of one row without curvature (the same expressions)."""
    for c in range(1, w - 1):
        ogu[c] = 0.5 * (mid[c + 1] - mid[c - 1])
    for c in range(w):
        ogv[c] = 0.5 * (dn[c] - up[c])
    ogu[0] = 0.5 * (mid[1] - mid[0])
    ogu[w - 1] = 0.5 * (mid[w - 1] - mid[w - 2])


@nb.njit(cache=True)
def _blur3_field(buf, r0, r1, c0, c1, value, gu, gv):
    """``cv2.GaussianBlur(buf[r0:r1, c0:c1], (3, 3), 0, borderType=BORDER_REPLICATE)`` into ``value`` and its
    gradients (:func:`field_derivatives` without curvature) into ``gu`` / ``gv``, all at (r0, c0), in one pass over
    the rows (a box of at least 2 x 2): the vertical pass reads three horizontally blurred rows kept in rotation, the
    gradients of a row are taken once the blurred row below it exists. Plain loops over three row arrays swapped by
    name, which LLVM vectorises."""
    k0 = np.float32(0.25)
    k1 = np.float32(0.5)
    w = c1 - c0
    above, row, below = np.empty(w, np.float32), np.empty(w, np.float32), np.empty(w, np.float32)
    _blur3_row(buf[r0, c0:c1], row, w)
    above[:] = row  # replicated border
    for r in range(r0, r1):
        if r + 1 < r1:
            _blur3_row(buf[r + 1, c0:c1], below, w)
        else:
            below[:] = row
        out = value[r, c0:c1]
        for c in range(w):
            out[c] = (above[c] + below[c]) * k0 + row[c] * k1
        if r > r0:  # the row above now has blurred rows on both sides
            q = r - 1
            _gradient_row(value[max(q - 1, r0), c0:c1], value[q, c0:c1], out, gu[q, c0:c1], gv[q, c0:c1], w)
        above, row, below = row, below, above
    q = r1 - 1
    _gradient_row(value[max(q - 1, r0), c0:c1], value[q, c0:c1], value[q, c0:c1], gu[q, c0:c1], gv[q, c0:c1], w)


def fill_distance_field(aligned: AlignedTimeSurface, field: TemporalDistanceField, t_us: int,
                        roi: tuple[int, int, int, int] | None = None, curvature: bool = False) -> None:
    """``field.compute(aligned, t_us, (0,), roi, curvature)``, bit for bit, from the patch list of the last compose.

    Writes the same attributes ``compute`` writes (``value`` / ``grad_u`` / ``grad_v`` of slot 0 in the box,
    ``hess`` with ``curvature``, ``box``, ``slots_ready``, ``t_us``).
    """
    if roi is None:
        r0, r1, c0, c1 = 0, field.height, 0, field.width
    else:
        r0, r1, c0, c1 = (int(v) for v in roi)
        r0, c0 = max(r0, 0), max(c0, 0)
        r1, c1 = min(r1, field.height), min(c1, field.width)
    eta_us = float(aligned.config.eta_ms) * 1e3
    cache = aligned.field_cache
    if cache.get("eta_us") != eta_us:
        cache["lut"], cache["shift"] = decay_lut(eta_us)
        cache["eta_us"] = eta_us
    field.t_us = int(t_us)
    if r1 - r0 < 2 or c1 - c0 < 2:
        field.slots_ready = ()
        field.box[:] = 0
        return
    k = int(field.config.blur_px)
    if k >= 2 and k % 2 == 0:
        k += 1
    touched, times = aligned.patch_times()
    if k == 3 and not curvature:
        _fused_fill(cache, field, touched, times, int(t_us), r0, r1, c0, c1)
        field.slots_ready = (0,)
        field.box[:] = (r0, r1, c0, c1)
        return
    # The box changes every step: views of two whole-image scratch rows (the TDF, and the blur of a box that is not
    # full-width), not two new arrays per step; _sparse_tdf overwrites all of ``buf``, the blur all of its output.
    flat = cache.get("flat")
    if flat is None or flat.shape[1] < field.height * field.width:
        flat = cache["flat"] = np.empty((2, field.height * field.width), np.float32)
    size = (r1 - r0) * (c1 - c0)
    buf = flat[0, :size].reshape(r1 - r0, c1 - c0)
    _sparse_tdf(touched, times, times.shape[0], np.int64(t_us), cache["lut"], int(cache["shift"]), r0, r1, c0, c1, buf)
    target = field.value[0, r0:r1, c0:c1]
    if k >= 3 and target.flags.c_contiguous:
        # Blur straight into the field (a full-width box is contiguous): no new image and no copy per step.
        img = cv2.GaussianBlur(buf, (k, k), 0, dst=target, borderType=cv2.BORDER_REPLICATE)
        if not np.shares_memory(img, field.value):
            target[...] = img
    else:
        img = cv2.GaussianBlur(buf, (k, k), 0, dst=flat[1, :size].reshape(r1 - r0, c1 - c0),
                               borderType=cv2.BORDER_REPLICATE) if k >= 3 else buf
        target[...] = img
    field_derivatives(img, r0, c0, bool(curvature), field.grad_u[0], field.grad_v[0], field.hess[0, 0], field.hess[1, 0], field.hess[2, 0])
    field.slots_ready = (0,)
    field.box[:] = (r0, r1, c0, c1)


def _fused_fill(cache: dict, field: TemporalDistanceField, touched, times, t_us: int, r0: int, r1: int, c0: int, c1: int) -> None:
    """The 3 px, no-curvature field of the box by :func:`_scatter_tdf` and :func:`_blur3_field` (see the module)."""
    lut = cache["lut"]
    buf = cache.get("tdf")
    if buf is None or buf.shape != (field.height, field.width) or cache.get("tdf_top") != lut[-1]:
        buf = cache["tdf"] = np.full((field.height, field.width), lut[-1], np.float32)
        cache["tdf_top"], cache["tdf_pixels"], cache["tdf_n"] = lut[-1], np.empty(field.height * field.width, np.int64), 0
    cache["tdf_n"] = int(_scatter_tdf(touched, times, times.shape[0], np.int64(t_us), lut, int(cache["shift"]), r0, r1, c0, c1,
                                      buf, cache["tdf_pixels"], int(cache["tdf_n"])))
    _blur3_field(buf, r0, r1, c0, c1, field.value[0], field.grad_u[0], field.grad_v[0])
