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
"""

from __future__ import annotations

import cv2
import numba as nb
import numpy as np

from evpose.frontend.distance_field import TemporalDistanceField, field_derivatives, decay_lut
from evpose.fusion.aligned_surface import AlignedTimeSurface


@nb.njit(cache=True)
def _sparse_tdf(touched, times, n, t_us, lut, shift, r0, r1, c0, c1, out):
    """TDF of the box (r0:r1, c0:c1) into ``out`` (its shape): the table's last bin (never fired or older than it)
    everywhere but at the listed pixels, whose timestamps are looked up exactly as ``_tdf_kernel`` does."""
    n_lut = lut.shape[0]
    half = np.int64(1) << max(shift - 1, 0) if shift > 0 else np.int64(0)
    oldest = t_us - ((np.int64(n_lut - 1) << shift) - half)
    top = lut[n_lut - 1]
    out[:, :] = top
    for i in range(n):
        r = touched[i, 0]
        c = touched[i, 1]
        if r < r0 or r >= r1 or c < c0 or c >= c1:
            continue
        s = times[i]
        if s <= oldest:
            continue  # already ``top``
        d = t_us - s
        if d < 0:
            d = 0
        out[r - r0, c - c0] = lut[(d + half) >> shift]


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
    # The box changes every step: views of two whole-image scratch rows (the TDF, and the blur of a box that is not
    # full-width), not two new arrays per step; _sparse_tdf overwrites all of ``buf``, the blur all of its output.
    flat = cache.get("flat")
    if flat is None or flat.shape[1] < field.height * field.width:
        flat = cache["flat"] = np.empty((2, field.height * field.width), np.float32)
    size = (r1 - r0) * (c1 - c0)
    buf = flat[0, :size].reshape(r1 - r0, c1 - c0)
    touched, times = aligned.patch_times()
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
