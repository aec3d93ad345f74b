"""Re-finding untracked local-map points near their projection (:class:`evpose.slam.system.EventSlam` inherits it).

After each pose estimate (and, when few map points are tracked, before it) the points of the local map that no track
carries are searched for near where the pose projects them: by KLT from the keyframe MCIs that saw them
(:mod:`evpose.slam.keyframe_search`) or by NCC patches (:mod:`evpose.slam.projection_search`); each point found gets a
new track. The methods read the system's ``cfg``, ``fe``, ``K`` and ``imu``.
"""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import SlamMap
from evpose.slam.keyframe_search import klt_refind_points
from evpose.slam.mci import MciResult
from evpose.slam.projection_search import SearchMatcher, refind_points


class PointRefinding:
    """Projection search of :class:`evpose.slam.system.EventSlam` (a mixin: it owns no state)."""

    def _matcher(self) -> SearchMatcher | None:
        """The projection search's matcher; None while it is off (event-inertial runs need ``search.event_inertial``)."""
        sc = self.cfg.search
        return sc.matcher if sc.enabled and (self.imu is None or sc.event_inertial) else None

    def _refind(self, m: SlamMap, mci: MciResult, T_wc: np.ndarray, radius: int) -> int:
        """Re-find untracked local-map points near their projection by ``T_wc``; each found point gets a new track. Returns how many."""
        matcher, sc, fe = self._matcher(), self.cfg.search, self.fe
        if matcher is None:
            return 0
        tracked = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
        tracked_pids = {fe.track_to_point[int(fe.ids[i])] for i in tracked}
        if matcher is SearchMatcher.KLT:
            pids, uv = klt_refind_points(m, mci.image8, self.K, T_wc, tracked_pids, fe.uv[tracked], self.cfg.tracking.local_window,
                                         radius, self.cfg.features, self.cfg.features.border_px, sc.klt_keyframes)
        else:
            pids, uv = refind_points(m, mci.image8, self.K, T_wc, tracked_pids, fe.uv[tracked], self.cfg.tracking.local_window, radius, sc)
        if not pids:
            return 0
        new_ids = np.arange(fe.next_id, fe.next_id + len(pids), dtype=np.int64)
        fe.next_id += len(pids)
        for tid, pid in zip(new_ids.tolist(), pids):
            p = m.points[pid]
            if fe.track_to_point.get(p.track_id) == pid:
                del fe.track_to_point[p.track_id]  # the point's old track died; the new one carries it
            p.track_id = tid
            fe.track_to_point[tid] = pid
        fe.ids = np.concatenate([fe.ids, new_ids])
        fe.uv = np.concatenate([fe.uv, uv.astype(np.float32)])
        return len(pids)
