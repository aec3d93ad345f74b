"""Starting a map in the SLAM system (:class:`evpose.slam.system.EventSlam` inherits it): the two-view initialisation
between a reference MCI and a later one, the first map points and the global BA of the two keyframes, and the re-join of
a fresh map onto the map lost while coasting (:mod:`evpose.slam.map_rejoin`). The methods read and set the system's
``fe``, ``atlas``, ``cfg``, ``K``, ``_init_cfg``, ``_next_point``, ``_state``, ``_rejoin`` and the times of its
last visual pose, and call its ``_replenish``, ``_matcher`` and ``_gyro_rotation``."""

from __future__ import annotations

import numpy as np

from evpose.slam.atlas import Keyframe, MapPoint, SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.initialization import initialize_two_view
from evpose.slam.keyframe_search import keep_keyframe_image
from evpose.slam.local_map import cull_points
from evpose.slam.map_rejoin import merge_into, rejoin_similarity
from evpose.slam.mci import MciResult
from evpose.slam.projection_search import SearchMatcher, store_patches
from evpose.slam.step_result import SlamStatus


class TwoViewInitialisation:
    """Map initialisation for :class:`evpose.slam.system.EventSlam` (a mixin: it owns no state)."""

    def _try_initialise(self, mci: MciResult) -> tuple[SlamStatus, str, np.ndarray | None]:
        fe, icfg = self.fe, self._init_cfg
        if fe.init_ref is None:
            self._replenish(mci.image8, mci.image)
            fe.init_ref = {int(t): uv.astype(np.float64) for t, uv in zip(fe.ids.tolist(), fe.uv)}
            fe.init_ref_t, fe.init_frames = mci.t_us, 0
            return SlamStatus.NOT_INITIALISED, f"initialisation reference set with {len(fe.init_ref)} features", None
        fe.init_frames += 1
        common = [i for i, t in enumerate(fe.ids.tolist()) if t in fe.init_ref]
        ids = fe.ids[common]
        p1 = np.array([fe.init_ref[int(t)] for t in ids]).reshape(-1, 2)
        p2 = fe.uv[common].astype(np.float64)
        res = initialize_two_view(self.K, p1, p2, icfg, self.cfg.seed)
        if not res.ok:
            if fe.init_frames >= icfg.max_frames or len(common) < icfg.min_matches:
                fe.init_ref = None  # start over from the next MCI with fresh features
            return SlamStatus.NOT_INITIALISED, f"initialisation: {res.reason}", None
        m = self.atlas.new_map() if (self.atlas.active is None or self.atlas.active.keyframes) else self.atlas.active
        kf0 = Keyframe(0, fe.init_ref_t, np.eye(4), {int(t): fe.init_ref[int(t)].copy() for t in ids})
        kf1 = Keyframe(1, mci.t_us, res.T_wc2, {int(t): uv.astype(np.float64) for t, uv in zip(fe.ids.tolist(), fe.uv)})
        # The first pose refers to its own keyframe: later BAs move the second one, and the first pose must not follow.
        m.keyframes = [kf0]
        m.add_pose(kf0.t_us, kf0.T_wc)
        m.keyframes.append(kf1)
        fe.track_to_point = {}
        for k in np.flatnonzero(res.good):
            tid = int(ids[k])
            pid = self._next_point
            self._next_point += 1
            m.points[pid] = MapPoint(pid, res.points[k].copy(), {0: p1[k].copy(), 1: p2[k].copy()}, tid, 1)
            fe.track_to_point[tid] = pid
        tc = self.cfg.tracking
        # Global BA of the two-view map (both keyframes' poses fixed: they define frame and scale).
        local_bundle_adjustment(m, self.K, 2, tc.ba_iterations, tc.ba_huber_px, n_fixed=2)
        cull_points(m, self.K, fe.track_to_point, tc)
        store_patches(m, kf1.id, mci.image8, self.cfg.search.patch_px)
        if self._matcher() is SearchMatcher.KLT:
            keep_keyframe_image(m, kf1, mci.image8, tc.local_window)
        m.add_pose(kf1.t_us, kf1.T_wc)
        fe.init_ref = None
        self._state = SlamStatus.OK
        self._last_visual_t, self._blank_us, self._after_blank_t = mci.t_us, 0, None
        self._last_pnp_t = mci.t_us
        if self._rejoin is not None:
            joined = self._try_rejoin(m)
            if joined is not None:
                return SlamStatus.OK, joined, self.atlas.active.keyframes[-1].T_wc.copy()
        return SlamStatus.OK, f"map {m.id} initialised ({res.model}, {len(m.points)} points, parallax {res.median_parallax_deg:.1f} deg)", m.keyframes[-1].T_wc.copy()

    def _try_rejoin(self, m: SlamMap) -> str | None:
        """Append the fresh two-view map ``m`` to the map lost while coasting, in that map's frame (:mod:`evpose.slam.map_rejoin`)."""
        cand, self._rejoin = self._rejoin, None
        old = cand.map
        if old is m or not old.traj_t or (m.keyframes[-1].t_us - old.traj_t[-1]) / 1e6 > self.cfg.inertial.rejoin_s:
            return None
        R0 = self._gyro_rotation(old.traj_t[-1], m.keyframes[0].t_us, old.traj_T[-1])
        R1 = self._gyro_rotation(old.traj_t[-1], m.keyframes[1].t_us, old.traj_T[-1])
        sim = None if R0 is None or R1 is None else rejoin_similarity(old, m, R0, R1, cand.v_cam)
        if sim is None:
            return None
        merge_into(old, m, *sim)
        self.atlas.maps.remove(m)
        return f"map {old.id} re-joined by a two-view map ({len(m.points)} points, scale {sim[2]:.3g} of it)"
