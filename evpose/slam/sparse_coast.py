"""Event-only coasting through a sparse scene (:attr:`evpose.slam.coast_config.CoastSettings.coast_gap_cap_ms`).

An event-only map that loses its point tracks coasts for at most ``coast_s`` of time. Where the scene is sparse the
window selection waits for its events and the MCIs come 35-55 ms apart instead of 8-15 ms, so a coast spends its time
in few MCIs; a blank wall (no MCI at all) is already left out of the count (``coast_blank_s``). Session 36: indoor seed
53's first map coasts from 0.03 s and runs out at 0.437 s in such a stretch (36-44 k events/s at 0.3-0.8 s against
100-400 k elsewhere), and no two-view start succeeds before 0.889 s, so the seed tracks 79.1 % of its time.
"""

from __future__ import annotations

import numpy as np


def sparse_gap_excess_s(traj_t: list[int], since_us: int, t_us: int, cap_ms: float) -> float:
    """How much of the time from ``since_us`` (the last visually tracked MCI) to ``t_us`` lies in gaps between
    consecutive MCIs beyond ``cap_ms`` each, seconds (0 when ``cap_ms`` <= 0). ``traj_t`` are the map's pose times
    (those after ``since_us`` are its coasted MCIs), us."""
    if cap_ms <= 0:
        return 0.0
    ts = [t for t in traj_t if t >= since_us] or [since_us]
    ts.append(t_us)
    gaps = np.diff(np.asarray(ts, np.int64)) / 1e6
    return float(np.clip(gaps - cap_ms / 1e3, 0.0, None).sum())
