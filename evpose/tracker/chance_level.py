"""The inlier share a registration would reach by chance where it stands: how densely recent events cover the field
around the registered points.

A map point counts as an inlier when the field reads below ``registration.inlier_threshold`` where it projects, i.e.
when a pixel near it fired recently. Where events cover the image densely (flicker, texture) a point of a wrong map
lands on one as often as a right one. The chance level is the share of the same points, displaced by a few pixels in
eight fixed directions, that read below the threshold: what the registered inlier share would be if the points
carried no information about where the events are. Only counted when asked (the acquisition window), so the
steady-state update does not pay for it.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from evpose.frontend.distance_field import TemporalDistanceField, bilinear_sample, polarity_slots

CHANCE_RADIUS_PX = 4.0
"""How far the chance samples are displaced, pixels: just past the inlier band of a 3 px-blurred edge, still in its
neighbourhood. A 10 px ring separated right from wrong maps less well (see :mod:`evpose.tracker.map_acquisition`)."""

_DIRECTIONS = np.array([[np.cos(a), np.sin(a)] for a in np.arange(8) * (np.pi / 4.0)], dtype=np.float64)


@nb.njit(cache=True)
def _chance_hits(value, gx, gy, box, slots, uv, dirs, radius, thr):
    """(hits, samples): displaced samples of the points inside the field that read below ``thr``."""
    hits = 0
    samples = 0
    for i in range(uv.shape[0]):
        u = uv[i, 0]
        v = uv[i, 1]
        if not (np.isfinite(u) and np.isfinite(v)):
            continue
        if not bilinear_sample(value, gx, gy, box, slots[i], u, v)[3]:
            continue
        for j in range(dirs.shape[0]):
            f, _, _, ok = bilinear_sample(value, gx, gy, box, slots[i], u + radius * dirs[j, 0], v + radius * dirs[j, 1])
            if ok:
                samples += 1
                if f < thr:
                    hits += 1
    return hits, samples


def chance_counts(field: TemporalDistanceField, uv: np.ndarray, polarity: np.ndarray | None, threshold: float) -> dict[str, int]:
    """``chance_hits`` of ``chance_samples``: the samples :data:`CHANCE_RADIUS_PX` around the registered projections
    ``uv`` (M, 2; NaN = behind the camera) that read below ``threshold`` in the slots of ``polarity`` (M,) (None =
    combined), eight per point inside the field. Their ratio is the chance level of the update's inlier share."""
    uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
    hits, samples = _chance_hits(field.value, field.grad_u, field.grad_v, field.box, polarity_slots(polarity, uv.shape[0]), uv,
                                 _DIRECTIONS, float(CHANCE_RADIUS_PX), float(threshold))
    return {"chance_hits": int(hits), "chance_samples": int(samples)}
