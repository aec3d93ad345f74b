"""Line landmarks in the SLAM system (:class:`evpose.slam.system.EventSlam` inherits it): tracks of straight MCI edges
are fed at every placed MCI of an event-only map, and a starved MCI is placed on the map's 3-D lines before it would
coast (:mod:`evpose.slam.line_landmarks`). The methods read the system's ``atlas``, ``fe``, ``cfg``, ``imu``, ``K``,
``_last_pnp_t`` and ``_lines``, and call its ``_refind`` and ``_new_keyframe``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from evpose.core.trajectory import invert_pose
from evpose.slam.atlas import SlamMap
from evpose.slam.coasting import drop_contradicted
from evpose.slam.edge_tracking import solve_pose_across_edges
from evpose.slam.line_landmarks import LineMap, detect_segments, line_measurements, update_tracks
from evpose.slam.mci import MciResult
from evpose.slam.step_result import SlamStatus


class LineAids:
    """Line landmarks for :class:`evpose.slam.system.EventSlam` (a mixin: its state is the system's ``_lines``)."""

    def _line_map(self, m: SlamMap) -> LineMap:
        lm = self._lines
        if lm.map_id != m.id or lm.restructured != m.restructured:
            # A new map, or one re-initialised in a new frame: its lines start over.
            lm = self._lines = LineMap(m.id, m.restructured)
        return lm

    def _lines_enabled(self) -> bool:
        return self.cfg.lines.enabled and self.imu is None

    def _lines_after_pose(self, m: SlamMap, mci: MciResult, T_wc: np.ndarray, segs: np.ndarray | None = None) -> None:
        """Feed the MCI placed at ``T_wc`` to the map's line tracks."""
        if not self._lines_enabled():
            return
        lc = self.cfg.lines
        if segs is None:
            segs = detect_segments(mci.image8, lc)
        update_tracks(self._line_map(m), self.K, T_wc, segs, mci.image8.shape, lc)

    def _line_track(self, m: SlamMap, mci: MciResult, T_pred: np.ndarray) -> tuple[SlamStatus, str, np.ndarray, bool] | None:
        """Event-only: the pose of a starved ``mci`` from the map's 3-D lines with ``T_pred`` (the coast) as the prior;
        None when off, too long since the last PnP pose, or not accepted."""
        lc, tc, fe = self.cfg.lines, self.cfg.tracking, self.fe
        if not self._lines_enabled() or (mci.t_us - self._last_pnp_t) / 1e6 > lc.max_span_s:
            return None
        lm = self._line_map(m)
        if len(lm.landmarks()) < lc.min_lines:
            return None
        segs = detect_segments(mci.image8, lc)
        T_pred_cw = invert_pose(T_pred)
        tracks, Xw, uv, nrm, _ = line_measurements(lm, self.K, T_pred_cw, segs, mci.image8.shape, lc)
        if len(tracks) < lc.min_lines:
            return None
        # Two residuals per line (its end points): min_points counts them.
        ec = replace(self.cfg.edge_tracking, min_points=2 * lc.min_lines)
        res = solve_pose_across_edges(self.K, Xw, uv, nrm, T_pred_cw, ec)
        if not res.ok:
            return None
        T_wc = invert_pose(res.T_cw)
        drop_contradicted(m, self.K, T_wc, fe.ids, fe.uv, fe.track_to_point, 2.0 * tc.reprojection_threshold_px)
        n_refound = self._refind(m, mci, T_wc, self.cfg.search.refine_radius_px)
        self._last_visual_t, self._blank_us, self._after_blank_t = mci.t_us, 0, None
        self._inliers = res.n_on_edge
        m.add_pose(mci.t_us, T_wc)
        T_wc = self._new_keyframe(m, mci.t_us, T_wc, mci.image8, adjust=False)
        if lc.update_from_lines:
            update_tracks(lm, self.K, T_wc, segs, mci.image8.shape, lc)
        return (SlamStatus.OK, f"line-tracked: {len(tracks)} lines, {res.n_on_edge} of {res.n_view} end points on them, "
                f"{res.info_gain:.0f}x the prior ({n_refound} re-found by projection), map {m.id}", T_wc.copy(), True)

    def _pnp_pose_with_lines(self, m: SlamMap, mci: MciResult, T_wc: np.ndarray, inliers: list[int]) -> tuple[np.ndarray, np.ndarray | None]:
        """The PnP pose ``T_wc`` re-solved with its inlier tracks (indices into the frontend's tracks) and the map's
        matched 3-D lines together, the PnP pose as a loose prior (``LineLandmarkConfig.refine_pnp``; else ``T_wc``
        itself); also returns the MCI's segments when it detected them."""
        lc, fe = self.cfg.lines, self.fe
        if not self._lines_enabled() or not lc.refine_pnp or not inliers:
            return T_wc, None
        Xw = np.stack([m.points[fe.track_to_point[int(fe.ids[i])]].xyz for i in inliers])
        uv = fe.uv[inliers].astype(np.float64)
        segs = detect_segments(mci.image8, lc)
        lm = self._line_map(m)
        T_cw = invert_pose(T_wc)
        tracks, Xl, uvl, nrml, _ = line_measurements(lm, self.K, T_cw, segs, mci.image8.shape, lc)
        if len(tracks) < lc.min_lines:
            return T_wc, segs
        # A point is two 1-D residuals, across x and across y.
        ex, ey = np.tile([1.0, 0.0], (len(Xw), 1)), np.tile([0.0, 1.0], (len(Xw), 1))
        X_all = np.concatenate([Xw, Xw, Xl])
        uv_all = np.concatenate([uv, uv, uvl])
        n_all = np.concatenate([ex, ey, nrml])
        ec = replace(self.cfg.edge_tracking, sigma_rotation_deg=lc.refine_sigma_rotation_deg,
                     sigma_translation_ratio=lc.refine_sigma_translation_ratio, min_points=1, min_inlier_ratio=0.0, min_info_gain=1.0)
        res = solve_pose_across_edges(self.K, X_all, uv_all, n_all, T_cw, ec)
        return (invert_pose(res.T_cw), segs) if res.T_cw is not None else (T_wc, segs)
