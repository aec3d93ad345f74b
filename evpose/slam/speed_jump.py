"""Event-only: how far a PnP pose's step departs from its map's own recent speed (``TrackingConfig.speed_jump_ratio``).

A monocular map's scale is only as good as its newest points: when a keyframe triangulates points at a wrong depth,
the next PnP poses placed on them step a multiple (or a fraction) of what the camera moved a moment before, while the
camera's speed changes smoothly (session 35, ``/tmp/s35/out35``: indoor seed 36's first map steps 1.2 -> 2.2 -> 4.0
times the true step within 60 ms of one keyframe and then collapses to 0.02 times it; seed 5's last map 0.7 -> 3.3).
"""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.coasting import trajectory_span


def speed_jump(m: SlamMap, t_us: int, T_wc: np.ndarray, span_us: int) -> float | None:
    """Speed of the step from the map's last pose to ``T_wc`` at ``t_us`` over the map's mean speed across its newest
    ``span_us`` of trajectory (camera centres, map units per us), unitless; None when the map has not moved for that
    long, the step takes no time, or the map stood still."""
    span = trajectory_span(m, span_us)
    dt = t_us - m.traj_t[-1] if m.traj_t else 0
    if span is None or dt <= 0:
        return None
    k, dt_ref = span
    v_ref = np.linalg.norm(m.traj_T[-1][:3, 3] - m.traj_T[k][:3, 3]) / dt_ref
    if not v_ref > 0:
        return None
    return float(np.linalg.norm(T_wc[:3, 3] - m.traj_T[-1][:3, 3]) / dt / v_ref)


def is_speed_jump(ratio: float | None, up: float, down: float = 0.0) -> bool:
    """Whether a step ``ratio`` times the map's recent speed is more than ``up`` times it or less than ``1 / down`` of it
    (a limit <= 1 disables its side)."""
    if ratio is None:
        return False
    return (up > 1.0 and ratio > up) or (down > 1.0 and ratio < 1.0 / down)
