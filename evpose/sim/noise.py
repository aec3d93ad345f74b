"""Sensor noise events: background activity (leak/shot noise) and hot pixels.

Background activity is a Poisson process per pixel with random polarity (shot
noise, dominant in the dark) plus a small ON bias (leak events); hot pixels
fire at a high fixed rate. All draws come from the caller's seeded generator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.events import EventArray


@dataclass(frozen=True)
class NoiseConfig:
    """Noise events added on top of the signal events."""

    background_rate_hz: float = field(default=0.1, metadata={"min": 0.0, "max": 50.0, "step": 0.05, "unit": "Hz/pixel"})
    """Mean background-activity rate per pixel, events per second."""
    leak_on_share: float = 0.6
    """Share of background events that are ON (leak events are ON), 0..1."""
    hot_pixels: int = field(default=0, metadata={"min": 0, "max": 100, "unit": "pixels"})
    """Number of hot pixels."""
    hot_rate_hz: float = 500.0
    """Event rate of each hot pixel, events per second."""


def noise_events(cfg: NoiseConfig, width: int, height: int, t0_us: int, t1_us: int, rng: np.random.Generator) -> EventArray:
    """Noise events in ``[t0_us, t1_us)``, sorted by time."""
    span = max(int(t1_us) - int(t0_us), 0)
    parts = []
    n_bg = int(rng.poisson(cfg.background_rate_hz * width * height * span * 1e-6)) if cfg.background_rate_hz > 0 else 0
    if n_bg:
        t = rng.integers(t0_us, t1_us, n_bg, dtype=np.int64)
        pix = rng.integers(0, width * height, n_bg)
        p = np.where(rng.random(n_bg) < cfg.leak_on_share, 1, -1)
        parts.append((t, pix % width, pix // width, p))
    if cfg.hot_pixels > 0 and span > 0:
        hot = rng.choice(width * height, size=min(cfg.hot_pixels, width * height), replace=False)
        for pix in hot:
            n = int(rng.poisson(cfg.hot_rate_hz * span * 1e-6))
            t = rng.integers(t0_us, t1_us, n, dtype=np.int64)
            parts.append((t, np.full(n, pix % width), np.full(n, pix // width), np.where(rng.random(n) < 0.8, 1, -1)))
    if not parts:
        return EventArray.empty()
    t, x, y, p = (np.concatenate([q[i] for q in parts]) for i in range(4))
    order = np.argsort(t, kind="stable")
    return EventArray.from_arrays(t[order], x[order], y[order], p[order].astype(np.int8))
