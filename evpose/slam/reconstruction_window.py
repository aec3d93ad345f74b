"""What the event-window selection (:mod:`evpose.slam.event_window`, the paper's Algorithm 1) hands on: a
:class:`ReconstructionWindow` of events and feature tracks per MCI, and the :class:`WindowEvent` its last tiny window
reported."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np


class WindowEvent(str, enum.Enum):
    """What the last tiny window did, for status reporting."""

    WAITING = "waiting"
    """Not enough events buffered for a tiny window yet."""
    LOW_RATE = "low_rate"
    """The tiny window's event rate was below ``th_e`` (camera still or too slow); state was reset."""
    GAP = "gap"
    """The stream held no event for longer than ``max_event_gap_ms`` (a dropout); state was reset at the gap."""
    NO_TEXTURE = "no_texture"
    """Too few FAST features in the tiny frame to start a reference."""
    TRACKING = "tracking"
    """Features tracked; displacement still below ``th_fd``."""
    DISPATCHED = "dispatched"
    """A reconstruction window was emitted."""


@dataclass
class ReconstructionWindow:
    """Events and feature tracks for one MCI."""

    t: np.ndarray
    """Event times, int64 us (sorted)."""
    x: np.ndarray
    """Undistorted columns, float64 px."""
    y: np.ndarray
    """Undistorted rows, float64 px."""
    p: np.ndarray
    """Polarities, int8 +1/-1."""
    ref_pts: np.ndarray
    """Feature positions in the reference tiny frame, float32 (M, 2) px."""
    cur_pts: np.ndarray
    """Their positions in the last tiny frame, float32 (M, 2) px."""
    t_ref_us: int
    """Mean event time of the reference tiny frame, us."""
    t_cur_us: int
    """Mean event time of the last tiny frame, us."""
    n_frames: int
    """Tiny frames in this window (``N_f``)."""
    median_displacement_px: float
    """``M_fd`` at dispatch, px."""
    forced: bool = False
    """Dispatched by the ``th_Nf`` rule or a feature loss, not by the displacement test."""
    blank_us: int = 0
    """Time spanned by the tiny windows rejected for their event rate (``th_e``) since the previous dispatch, with the
    tiny frames collected before each and dropped with it: the camera saw little but noise then (blank walls), us."""
    whole_pts: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2), np.float32))
    """Tracks that cover the whole window (``EventWindowSelector(carry_tracks=True)``): the previous window's features,
    from its reference tiny frame (where this window's overlap starts) through every tiny frame to this window's last
    one, float32 (F, M, 2) px; only tracks alive in every frame; empty without an overlap or when not carried."""
    whole_t_us: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    """Mean event time of each of those tiny frames, int64 (F,) us."""
    n_overlap: int = 0
    """How many of the first events are the previous window's (``EventWindowConfig.overlap``), events."""

    @property
    def t_end_us(self) -> int:
        return int(self.t[-1]) if len(self.t) else 0
