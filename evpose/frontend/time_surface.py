"""Separated-polarity time surface (SP-TS): one last-timestamp map per polarity with exponential decay.

EV-Pose section IV-A: ``T(x, t) = exp(-(t - t_last(x)) / eta)``, never-fired pixels
are 0, the combined surface is the max of the two polarities. Events are stored
in ideal-pinhole pixel coordinates (the calibration's ``undistortion_table``,
rounded to the nearest pixel) so the tracker can project map points with ``K``
alone; events whose undistorted position leaves the image are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.frontend.noise_filter import NEVER_US

POLARITY_SLOT = {1: 0, -1: 1}
"""Index of each polarity's map in :attr:`SeparatedTimeSurface.last_timestamps`."""


@dataclass
class TimeSurfaceConfig:
    """SP-TS settings."""

    eta_ms: float = field(default=10.0, metadata={"min": 0.5, "max": 200.0, "step": 0.5, "unit": "ms"})
    """Exponential decay constant ``eta``, milliseconds: a pixel that fired ``eta`` ago reads 1/e.

    ``stpe`` on the 2 s simulated landing, seeds 0-3, mean ATE at 346x260 / 240x180 (``field_lag_ms`` with it):
    10 ms (4.5 ms) 24.5 / 31.1 mm; 12 ms (5.0) 25.6 / 30.0; 15 ms (5.5) 25.3 / 28.9; 15 ms (4.5) 25.1 / 29.7;
    seed 0 only: 7 ms (3.5) 18.8 / 37.3, 20 ms (6.5) 21.8 / 28.8 against 18.7 / 29.9. No setting helps both.
    Session 29, ``full`` at 240x180 (seeds 0-7, 6.955 mm; ``/tmp/s29/reg29/run.py``): 14.4 ms (the pixel-angle ratio,
    edges crossing a coarse pixel 1.44x slower) 8.750 mm, 7 ms 7.259 mm."""


@nb.njit(cache=True)
def _update_kernel(t, x, y, p, keep, width, lut, last_flat, combined_flat):
    """Stamp each kept event into its polarity's map and the combined map; ``lut``: sensor -> ideal pixel (-1 = outside),
    empty for the identity (see :func:`kernel_lut`).

    Taking the mask here (instead of indexing the batch first) saves a copy of every column per step.
    """
    plane = combined_flat.shape[0]
    stored = 0
    for i in range(t.shape[0]):
        if not keep[i]:
            continue
        j = lut[np.int64(y[i]) * width + np.int64(x[i])] if lut.shape[0] else np.int64(y[i]) * width + np.int64(x[i])
        if j < 0:
            continue
        off = 0 if p[i] > 0 else plane
        last_flat[off + j] = t[i]
        combined_flat[j] = t[i]
        stored += 1
    return stored


@nb.njit(cache=True)
def decay_image(last, t_us, inv_eta_us, out):
    """``out = exp(-(t - last) * inv_eta)`` (0 where never fired, 1 for events after ``t``), float32 (H, W)."""
    h, w = last.shape
    for r in range(h):
        for c in range(w):
            d = t_us - last[r, c]
            if d < 0:
                d = 0
            out[r, c] = np.float32(np.exp(-np.float64(d) * inv_eta_us))
    return out


def ideal_pixel_lut(width: int, height: int, calibration: CameraCalibration | None) -> np.ndarray:
    """int32 (H*W,): linear ideal-pinhole pixel index of every sensor pixel, -1 if it falls outside the image."""
    if calibration is None or calibration.model is DistortionModel.NONE:
        return np.arange(width * height, dtype=np.int32)
    table = calibration.undistortion_table
    col = np.rint(table[..., 0]).astype(np.int64)
    row = np.rint(table[..., 1]).astype(np.int64)
    inside = (col >= 0) & (col < width) & (row >= 0) & (row < height)
    return np.where(inside, row * width + col, -1).astype(np.int32).ravel()


_IDENTITY_LUT = np.zeros(0, np.int32)


def kernel_lut(lut: np.ndarray) -> np.ndarray:
    """``lut`` as the per-event kernels take it: empty when it is the identity (no distortion), so they compute the
    pixel index instead of reading the table, a cache miss per event on a 0.36 MB table at 346x260."""
    return _IDENTITY_LUT if np.array_equal(lut, np.arange(lut.shape[0], dtype=lut.dtype)) else lut


class SeparatedTimeSurface:
    """Per-polarity last-timestamp maps over the ideal-pinhole image, with decayed images on demand."""

    def __init__(self, config: TimeSurfaceConfig, width: int, height: int, calibration: CameraCalibration | None = None):
        self.config = config
        self.width = int(width)
        self.height = int(height)
        self._lut = ideal_pixel_lut(self.width, self.height, calibration)
        self._kernel_lut = kernel_lut(self._lut)
        self._last = np.full((2, self.height, self.width), NEVER_US, dtype=np.int64)
        # The newest stamp of either polarity, kept alongside so the combined field needs no per-pixel max.
        self._combined = np.full((self.height, self.width), NEVER_US, dtype=np.int64)

    @property
    def inv_eta_us(self) -> float:
        return 1.0 / (float(self.config.eta_ms) * 1e3)

    @property
    def last_timestamps(self) -> np.ndarray:
        """int64 (2, H, W) microseconds: slot 0 = ON (+1), slot 1 = OFF (-1); ``NEVER_US`` where never fired."""
        return self._last

    def update(self, events: EventArray, keep: np.ndarray | None = None) -> int:
        """Stamp a time-sorted batch (only ``keep`` events if a mask is given); returns how many were stored."""
        if len(events) == 0:
            return 0
        flat = self._last.reshape(-1)
        comb = self._combined.reshape(-1)
        if keep is None:
            keep = np.ones(len(events), dtype=np.bool_)
        return int(_update_kernel(events.t, events.x, events.y, events.p, keep, self.width, self._kernel_lut, flat, comb))

    def combined_last(self) -> np.ndarray:
        """int64 (H, W): the newest timestamp of either polarity (the combined surface's source; a view)."""
        return self._combined

    def last_of(self, polarity: int) -> np.ndarray:
        """int64 (H, W) last-timestamp map of polarity +1, -1 or 0 (combined); a view."""
        return self._combined if polarity == 0 else self._last[POLARITY_SLOT[int(polarity)]]

    def image(self, t_us: int, polarity: int = 0) -> np.ndarray:
        """Decayed surface at ``t_us``: float32 (H, W) in [0, 1]; polarity +1, -1 or 0 (max of both)."""
        last = self.last_of(polarity)
        out = np.empty((self.height, self.width), dtype=np.float32)
        return decay_image(last, np.int64(t_us), self.inv_eta_us, out)

    def reset(self) -> None:
        self._last.fill(NEVER_US)
        self._combined.fill(NEVER_US)

    def snapshot(self) -> dict:
        return {"last": self._last.copy(), "combined": self._combined.copy()}

    def restore(self, state: dict) -> None:
        np.copyto(self._last, state["last"])
        np.copyto(self._combined, state["combined"])
