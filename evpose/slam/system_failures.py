"""What the SLAM system does when visual tracking fails on an MCI (:class:`evpose.slam.system.EventSlam` inherits it).

E-I-C2/C3 bridge the failure and keep the map: a metric map is propagated by the IMU, a map the IMU initialisation
has not reached yet coasts on the gyro rotation and its recent velocity. Event-only runs coast on the map's recent
motion for at most ``TrackingConfig.coast_s`` (time at a blank wall excepted, ``coast_blank_s``). Otherwise, or
when the bridge runs too long, the map is lost and the next two-view initialisation opens a new map of the atlas.
The methods read the system's ``atlas``, ``fe``, ``cfg``, ``imu``, ``K``, ``_last_visual_t`` and ``_blank_us`` and
call its ``_new_keyframe`` and ``_imu_prediction``; refusing a PnP pose that steps off the map's speed reads its
``_speed_refusals``.
"""

from __future__ import annotations

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.coasting import camera_frame_velocity, coast_pose, drop_contradicted, trajectory_span
from evpose.slam.edge_tracking import measure_across_edges, solve_pose_across_edges
from evpose.slam.event_coasting import drop_past_blank, drop_unconfirmed_poses, event_only_coast_pose, held_motion_end, mature_coast_pose
from evpose.slam.inertial import InertialConfiguration
from evpose.slam.inertial_guards import discard_map, young_lost_map
from evpose.slam.map_rejoin import RejoinCandidate
from evpose.slam.mci import MciResult
from evpose.slam.sparse_coast import sparse_gap_excess_s
from evpose.slam.speed_jump import is_speed_jump, speed_jump
from evpose.slam.step_result import SlamStatus


class VisualFailureHandling:
    """Bridging, coasting and losing maps for :class:`evpose.slam.system.EventSlam` (a mixin: its only state is the
    coast velocity held across re-localisations, ``_coast_hold``)."""

    _coast_hold: tuple[int, int, np.ndarray] | None = None
    """(map id, time of the newest pre-initialisation coasted pose in us, the camera-frame velocity it coasted on), for
    ``InertialConfig.coast_hold_velocity``."""

    def _lose(self, reason: str) -> tuple[SlamStatus, str, None, bool]:
        m = self.atlas.active
        if m is not None:
            m.lost_reason = reason
            if self.imu is not None and young_lost_map(m, self.cfg.inertial.discard_lost_young_s) and (self._rejoin is None or self._rejoin.map is not m):
                discard_map(m, reason)  # InertialConfig.discard_lost_young_s: ORB-SLAM3 resets such a map
        self._state = SlamStatus.NOT_INITIALISED
        self.fe.track_to_point = {}
        self.fe.init_ref = None
        # The next successful initialisation opens a new map of the atlas.
        self.atlas.new_map()
        return SlamStatus.LOST, f"tracking lost: {reason}", None, False

    def _bridge_or_lose(self, mci: MciResult, reason: str, R_prior: np.ndarray | None = None) -> tuple[SlamStatus, str, np.ndarray | None, bool]:
        """E-I-C2/C3: keep the map through a visual failure, the pose predicted without the images (``SlamStatus.INERTIAL``).

        A metric map is propagated by the preintegrated IMU; a map the IMU initialisation has not reached yet coasts on
        the gyro rotation and its recent camera-frame velocity (``InertialConfig.coast_s``). A keyframe at the predicted
        pose lets new points be triangulated, so the map can be re-localised on the next MCIs.
        """
        m, fe, ic, tc = self.atlas.active, self.fe, self.cfg.inertial, self.cfg.tracking
        gap_s = (mci.t_us - self._last_visual_t) / 1e6
        if self.imu is None:
            return self._coast_event_only(mci, reason, gap_s, R_prior)
        if ic.configuration is InertialConfiguration.C1 or gap_s > ic.max_bridge_s:
            return self._lose(reason)
        if m.imu_initialised:
            T_wc, how = self._imu_prediction(mci.t_us), "propagated by the IMU"
        else:
            v = self._coast_velocity(m)
            if gap_s > ic.coast_s or R_prior is None or v is None:
                self._rejoin = RejoinCandidate(m, v) if v is not None and ic.rejoin_s > 0 else None
                return self._lose(reason)
            T_wc, how = coast_pose(m, mci.t_us, R_prior, v), "coasted on the gyro and the last velocity (IMU not initialised)"
            self._coast_hold = (m.id, mci.t_us, v)
        if T_wc is None:
            return self._lose(reason)
        drop_contradicted(m, self.K, T_wc, fe.ids, fe.uv, fe.track_to_point, 2.0 * tc.reprojection_threshold_px)
        m.add_pose(mci.t_us, T_wc)
        T_wc = self._new_keyframe(m, mci.t_us, T_wc, mci.image8, adjust=m.imu_initialised or ic.coast_ba,
                                  triangulate=m.imu_initialised or ic.coast_triangulate)
        return SlamStatus.INERTIAL, f"visual tracking failed ({reason}); pose {how}, map {m.id} kept", T_wc.copy(), True

    def _coast_velocity(self, m) -> np.ndarray | None:
        """Camera-frame velocity a map the IMU initialisation has not reached coasts on: that of its newest poses over
        ``InertialConfig.coast_velocity_span_s``, or, with ``coast_hold_velocity``, the previous coast's when that span
        reaches back to a coasted pose (the difference would measure the re-localisation's correction, not motion)."""
        ic = self.cfg.inertial
        hold = self._coast_hold
        if ic.coast_hold_velocity and hold is not None and hold[0] == m.id and m.traj_t:
            span = trajectory_span(m, int(ic.coast_velocity_span_s * 1e6))
            if span is None or m.traj_t[span[0]] <= hold[1]:
                return hold[2]
        return camera_frame_velocity(m, int(ic.coast_velocity_span_s * 1e6))

    def _coast_event_only(self, mci: MciResult, reason: str, gap_s: float, R_wc: np.ndarray | None = None) -> tuple[SlamStatus, str, np.ndarray | None, bool]:
        """Event-only: keep the map through a visual failure of at most ``TrackingConfig.coast_s`` (``SlamStatus.COASTING``).

        ``R_wc``: an orientation measured for this MCI (the visual gyro, :mod:`evpose.slam.visual_gyro`) replaces the
        coast's constant-rate one."""
        m, fe, tc = self.atlas.active, self.fe, self.cfg.tracking
        if tc.coast_s <= 0:
            return self._lose(reason)
        # Blank stretches (no MCI: the event rate fell below th_e) up to coast_blank_s do not use up the coast.
        gap_s -= min(self._blank_us / 1e6, tc.coast_blank_s)
        # Sparse stretches (TrackingConfig.coast_gap_cap_ms, off by default): each gap between MCIs counts up to its cap.
        gap_s -= max(sparse_gap_excess_s(m.traj_t, self._last_visual_t, mci.t_us, tc.coast_gap_cap_ms) - self._blank_us / 1e6, 0.0)
        after_s = (mci.t_us - self._after_blank_t) / 1e6 if self._after_blank_t is not None else 0.0
        if tc.coast_blank_s > 0 and after_s > tc.coast_after_blank_s:
            gap_s = np.inf  # crossed a blank wall on dead reckoning and not placed again right after it
        end = held_motion_end(m.traj_t, self._last_visual_t) if tc.coast_hold_motion else -1
        T_wc = None
        if gap_s <= tc.coast_s and tc.coast_mature_span_s > 0:
            # TrackingConfig.coast_mature_span_s: a long-lived map holds its longer-term motion, not its last step's.
            T_wc = mature_coast_pose(m, mci.t_us, int(tc.coast_mature_span_s * 1e6), held_motion_end(m.traj_t, self._last_visual_t))
        if T_wc is None and gap_s <= tc.coast_s:
            T_wc = event_only_coast_pose(m, mci.t_us, int(tc.coast_span_s * 1e6), end)
        if T_wc is None and gap_s <= tc.coast_s and tc.coast_young_span_s > 0 and m.traj_t:
            # A young map: hold the motion of its whole trajectory, if that spans long enough to mean anything.
            span_us = m.traj_t[end] - m.traj_t[0]
            if span_us >= tc.coast_young_span_s * 1e6:
                T_wc = event_only_coast_pose(m, mci.t_us, span_us, end)
        if T_wc is None:
            if tc.coast_drop_unconfirmed or self._mature_unconfirmed(m):
                drop_unconfirmed_poses(m, self._last_visual_t)
            elif tc.coast_drop_past_blank:
                drop_past_blank(m, self._after_blank_t, self._last_visual_t)
            return self._lose(reason)
        if R_wc is not None:
            T_wc = T_wc.copy()
            T_wc[:3, :3] = R_wc
        edge = self._line_track(m, mci, T_wc) or self._edge_track(m, mci, T_wc)
        if edge is not None:
            return edge
        T_written = self._written_coast(m, mci) if R_wc is None else None
        drop_contradicted(m, self.K, T_wc, fe.ids, fe.uv, fe.track_to_point, 2.0 * tc.reprojection_threshold_px)
        m.add_pose(mci.t_us, T_wc)
        if T_written is not None:
            m.add_written_alternative(mci.t_us, T_written)
        # No BA on a keyframe at a predicted pose (InertialConfig.coast_ba: with one fixed keyframe it slid along the scale).
        # No points from dead reckoning either (TrackingConfig.coast_triangulate off): they let PnP place the map again
        # on the coast's own error.
        triangulate = self._coast_triangulates(m, mci.t_us, T_wc)
        T_wc = self._new_keyframe(m, mci.t_us, T_wc, mci.image8, adjust=False, triangulate=triangulate)
        if self.cfg.lines.update_from_coast:
            self._lines_after_pose(m, mci, T_wc)
        return SlamStatus.COASTING, f"visual tracking failed ({reason}); pose coasted on the map's recent motion, map {m.id} kept", T_wc.copy(), True

    def _mature_unconfirmed(self, m) -> bool:
        """Whether a coast that ends in a loss leaves the map's trajectory under ``TrackingConfig.coast_drop_mature_s``:
        the map spans at least that up to its last PnP pose (its coast is neither written on the visual gyro's rotations,
        ``VisualGyroConfig.written_coasts_max_map_s``, nor anything the images confirmed)."""
        lim = self.cfg.tracking.coast_drop_mature_s
        return lim > 0 and bool(m.traj_t) and (self._last_pnp_t - m.traj_t[0]) / 1e6 >= lim

    def _coast_triangulates(self, m, t_us: int, T_wc: np.ndarray) -> bool:
        """Whether the keyframe at coasted pose ``T_wc`` triangulates: always with ``TrackingConfig.coast_triangulate``;
        without it only on a map with at least ``coast_triangulate_min_map_s`` of trajectory up to its last PnP pose
        whose coast has turned at most ``coast_triangulate_max_rate_dps`` per second since that pose (a landing's slow
        spiral, whose map would otherwise run out of points, not a room's turn)."""
        tc = self.cfg.tracking
        if tc.coast_triangulate:
            return True
        if tc.coast_triangulate_max_rate_dps <= 0 or self._last_pnp_t not in m.traj_t:
            return False
        if (self._last_pnp_t - m.traj_t[0]) / 1e6 < tc.coast_triangulate_min_map_s:
            return False
        R_rel = m.traj_T[m.traj_t.index(self._last_pnp_t)][:3, :3].T @ T_wc[:3, :3]
        deg = np.degrees(np.arccos(np.clip((np.trace(R_rel) - 1.0) / 2.0, -1.0, 1.0)))
        return bool(deg <= tc.coast_triangulate_max_rate_dps * max(t_us - self._last_pnp_t, 0) / 1e6)

    def _edge_track(self, m, mci: MciResult, T_pred: np.ndarray) -> tuple[SlamStatus, str, np.ndarray, bool] | None:
        """Event-only: the pose of ``mci`` from the map's points on its edges with ``T_pred`` (the coast) as the prior
        (:mod:`evpose.slam.edge_tracking`); None when it is off, too long since the last PnP pose, or not accepted."""
        ec, tc, fe = self.cfg.edge_tracking, self.cfg.tracking, self.fe
        if not ec.enabled or (mci.t_us - self._last_pnp_t) / 1e6 > ec.max_span_s or not m.points:
            return None
        pts = [p for _, p in sorted(m.points.items()) if p.patch is not None]
        if len(pts) < ec.min_points:
            return None
        Xw = np.stack([p.xyz for p in pts])
        T_pred_cw = invert_pose(T_pred)
        idx, uv, nrm = measure_across_edges(mci.image8, self.K, T_pred_cw, Xw, [p.patch for p in pts], ec)
        res = solve_pose_across_edges(self.K, Xw[idx], uv, nrm, T_pred_cw, ec)
        if not res.ok:
            return None
        T_wc = invert_pose(res.T_cw)
        drop_contradicted(m, self.K, T_wc, fe.ids, fe.uv, fe.track_to_point, 2.0 * tc.reprojection_threshold_px)
        n_refound = self._refind(m, mci, T_wc, self.cfg.search.refine_radius_px)
        if ec.resets_coast:
            self._last_visual_t, self._blank_us, self._after_blank_t = mci.t_us, 0, None
        self._inliers = res.n_on_edge
        m.add_pose(mci.t_us, T_wc)
        T_wc = self._new_keyframe(m, mci.t_us, T_wc, mci.image8, adjust=ec.adjust_keyframes)
        return (SlamStatus.OK, f"edge-tracked: {res.n_on_edge} of {res.n_view} map points on edges, {res.info_gain:.0f}x the "
                f"prior ({n_refound} re-found by projection), map {m.id}", T_wc.copy(), True)

    def _speed_jump(self, m: SlamMap, t_us: int, T_wc: np.ndarray) -> str | None:
        """Why the PnP pose ``T_wc`` is refused for stepping off the map's recent speed (``TrackingConfig.speed_jump_ratio``),
        or None (event-only; off by default)."""
        tc = self.cfg.tracking
        if self.imu is not None or max(tc.speed_jump_ratio, tc.speed_drop_ratio) <= 1.0 or not m.traj_t:
            return None
        if t_us - m.traj_t[0] < tc.speed_jump_min_age_s * 1e6:
            return None
        if 0 < tc.speed_jump_max_refusals <= self._speed_refusals:
            return None  # PnP has kept disagreeing with the coast: the map moved on, not one step
        r = speed_jump(m, t_us, T_wc, int(tc.coast_span_s * 1e6))
        return f"PnP step {r:.2f} times the map's recent speed" if is_speed_jump(r, tc.speed_jump_ratio, tc.speed_drop_ratio) else None
