"""ESIM-style event generation from a sequence of log-intensity images.

Each pixel keeps a reference log intensity ``L_ref``. Between two renders at
``t0`` and ``t1`` the pixel's log intensity is taken as linear in time (ESIM);
every time it moves a full contrast threshold away from ``L_ref`` an event is
emitted at the linearly interpolated crossing time and ``L_ref`` moves by one
threshold. Thresholds ``C+``/``C-`` vary per pixel (Gaussian spread, fixed by
the seed). An event closer than the refractory period to the pixel's previous
event is dropped (the reference still moves: the pixel's comparator reset is
what is lost, not the brightness change). Noise (background activity, hot
pixels) is added separately by :mod:`evpose.sim.noise`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.core.events import EventArray


@dataclass(frozen=True)
class EsimConfig:
    """Contrast thresholds and timing of the simulated pixels."""

    c_pos: float = field(default=0.4, metadata={"min": 0.05, "max": 1.5, "step": 0.01, "unit": "log intensity"})
    """ON contrast threshold C+, log-intensity units."""
    c_neg: float = field(default=0.4, metadata={"min": 0.05, "max": 1.5, "step": 0.01, "unit": "log intensity"})
    """OFF contrast threshold C-, log-intensity units."""
    c_sigma: float = field(default=0.03, metadata={"min": 0.0, "max": 0.3, "step": 0.005, "unit": "log intensity"})
    """Per-pixel standard deviation of both thresholds (fixed pattern), log-intensity units."""
    c_min: float = 0.05
    """Lower clamp of a pixel's threshold, log-intensity units."""
    refractory_us: int = field(default=100, metadata={"min": 0, "max": 10000, "unit": "us"})
    """Minimum time between two events of one pixel, microseconds."""


def threshold_maps(cfg: EsimConfig, width: int, height: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel C+ and C- (flattened row-major, float64)."""
    n = width * height
    cp = np.maximum(cfg.c_pos + cfg.c_sigma * rng.standard_normal(n), cfg.c_min)
    cn = np.maximum(cfg.c_neg + cfg.c_sigma * rng.standard_normal(n), cfg.c_min)
    return cp, cn


@nb.njit(cache=True)
def _count(l0, l1, ref, cp, cn):
    n = 0
    for k in range(l0.shape[0]):
        d = l1[k] - ref[k]
        if d >= cp[k]:
            n += int(d / cp[k])
        elif -d >= cn[k]:
            n += int(-d / cn[k])
    return n + l0.shape[0] // 64 + 16  # slack for float rounding in the loop below


@nb.njit(cache=True)
def _emit(l0, l1, ref, cp, cn, last_t, t0, t1, refractory, width, out_t, out_x, out_y, out_p):
    n = 0
    dt = float(t1 - t0)
    for k in range(l0.shape[0]):
        a = l0[k]
        b = l1[k]
        d = b - a
        r = ref[k]
        if d > 0:
            c = cp[k]
            while b - r >= c and n < out_t.shape[0]:
                r += c
                te = t0 + np.int64(np.floor((r - a) / d * dt))
                if te - last_t[k] >= refractory:
                    out_t[n] = te
                    out_x[n] = k % width
                    out_y[n] = k // width
                    out_p[n] = 1
                    n += 1
                    last_t[k] = te
        elif d < 0:
            c = cn[k]
            while r - b >= c and n < out_t.shape[0]:
                r -= c
                te = t0 + np.int64(np.floor((r - a) / d * dt))
                if te - last_t[k] >= refractory:
                    out_t[n] = te
                    out_x[n] = k % width
                    out_y[n] = k // width
                    out_p[n] = -1
                    n += 1
                    last_t[k] = te
        ref[k] = r
    return n


class EventGenerator:
    """Stateful per-pixel comparator: feed it log images in time order, get events back."""

    def __init__(self, cfg: EsimConfig, width: int, height: int, rng: np.random.Generator):
        self.cfg = cfg
        self.width = width
        self.height = height
        self.c_pos, self.c_neg = threshold_maps(cfg, width, height, rng)
        self.ref: np.ndarray | None = None
        self.prev: np.ndarray | None = None
        self.t_prev = 0
        self.last_t = np.full(width * height, np.iinfo(np.int64).min // 2, np.int64)

    def reset(self, log_image: np.ndarray, t_us: int) -> None:
        """Start from ``log_image`` at ``t_us`` without emitting events."""
        self.prev = np.ascontiguousarray(log_image, np.float64).ravel().copy()
        self.ref = self.prev.copy()
        self.t_prev = int(t_us)

    def step(self, log_image: np.ndarray, t_us: int) -> EventArray:
        """Events between the previous image and ``log_image`` at ``t_us``, sorted by time (stable in pixel order)."""
        cur = np.ascontiguousarray(log_image, np.float64).ravel()
        cap = _count(self.prev, cur, self.ref, self.c_pos, self.c_neg)
        ot = np.empty(cap, np.int64)
        ox = np.empty(cap, np.uint16)
        oy = np.empty(cap, np.uint16)
        op = np.empty(cap, np.int8)
        n = _emit(self.prev, cur, self.ref, self.c_pos, self.c_neg, self.last_t, np.int64(self.t_prev), np.int64(t_us), np.int64(self.cfg.refractory_us), self.width, ot, ox, oy, op)
        self.prev = cur.copy()
        self.t_prev = int(t_us)
        order = np.argsort(ot[:n], kind="stable")
        return EventArray(ot[:n][order], ox[:n][order], oy[:n][order], op[:n][order])
