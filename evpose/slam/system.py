"""The SLAM system: events -> tiny windows -> MCIs -> KLT tracks -> two-view init / local-map tracking -> keyframes, local BA -> atlas.

Everything runs in one thread in a fixed order (the paper's implementation uses
threads and is, by its own README, unstable); OpenCV's RANSAC generator is
re-seeded before every call, so a run repeats bit for bit.

Associations are KLT tracks; when the sharpest MCI hypothesis differs from the
previous MCI's and KLT fails on it, the previous hypothesis's image is tracked
instead (``MciConfig.keep_hypothesis_survival``). Untracked local-map points
are re-found near their projection after each pose estimate (``SlamConfig.search``:
KLT from keyframe MCIs, :mod:`evpose.slam.keyframe_search`, or NCC patches).

Event-inertial mode adds: the gyro rotation between MCIs as a prior of pose
tracking (and, before the IMU initialisation, loosely, of the visual local BA),
the IMU initialisation on keyframes thinned in time, a full inertial BA right
after it, IMU-predicted pose guesses, and (E-I-C2/C3) IMU bridges over visual
failures that keep the map instead of opening a new one.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from evpose.core.camera import CameraCalibration
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.trajectory import invert_pose
from evpose.errors import InputError
from evpose.slam.atlas import Atlas, SlamMap
from evpose.slam.bundle_adjustment import local_bundle_adjustment
from evpose.slam.coasting import constant_velocity_pose
from evpose.slam.config import SlamConfig, SlamMode
from evpose.slam.event_window import WINDOW_REASONS, EventWindowSelector
from evpose.slam.reconstruction_window import ReconstructionWindow
from evpose.slam.features import FrontendTracks, detect_features, has_support, track_features
from evpose.slam.track_step import step_consistent
from evpose.slam.fine_grid import track_features_fine, use_fine_grid
from evpose.slam.geometry import pose_jump_depths
from evpose.slam.inertial import InertialConfiguration
from evpose.slam.inertial_ba import inertial_local_bundle_adjustment
from evpose.slam.inertial_guards import anchored_window, starts_at_rejoin
from evpose.slam.inertial_trajectory import carry_relative_scale, keyframe_positions
from evpose.slam.map_restructure import maybe_restructure
from evpose.slam.map_rejoin import RejoinCandidate
from evpose.slam.keyframe_scale import check_new_points
from evpose.slam.keyframe_step import check_keyframe_step, keyframe_step_collapse
from evpose.slam.local_map import (cull_points, insert_keyframe, need_keyframe, triangulate_new_points, visual_ba_window, young_map,
                                   young_triangulation)
from evpose.slam.event_image import to_uint8
from evpose.slam.mci import Hypothesis, MciGenerator, MciResult, MotionPrior
from evpose.slam.parallax_warp import points_in_view
from evpose.slam.keyframe_search import keep_keyframe_image
from evpose.slam.projection_search import SearchMatcher, store_patches
from evpose.slam.young_scale import speed_factor_hook
from evpose.slam.step_result import SlamFailure, SlamStatus, SlamStepResult
from evpose.slam.system_failures import VisualFailureHandling
from evpose.slam.system_gaps import StreamGaps, imu_holes
from evpose.slam.system_gyro import GyroAids
from evpose.slam.system_initialisation import TwoViewInitialisation
from evpose.slam.system_inertial import InertialMaps
from evpose.slam.system_lines import LineAids
from evpose.slam.system_refind import PointRefinding
from evpose.slam.line_landmarks import LineMap
from evpose.slam.track_fusion import fuse_tracks
from evpose.slam.tracking import PoseEstimate, estimate_pose


class EventSlam(TwoViewInitialisation, GyroAids, InertialMaps, VisualFailureHandling, LineAids, StreamGaps, PointRefinding):
    """Map-free event(-inertial) SLAM. Feed events with :meth:`step`; read maps from :attr:`atlas`."""

    def __init__(self, config: SlamConfig, calibration: CameraCalibration, imu: ImuSamples | None = None):
        if calibration is None:
            raise InputError(None, "SLAM needs a camera calibration")
        if config.mode is SlamMode.EVENT_INERTIAL and (imu is None or len(imu) < 2):
            raise InputError(None, "event-inertial mode needs IMU samples; the recording has none")
        self.cfg = config
        self._tc_uninit = config.tracking
        """Tracking settings of maps the IMU initialisation has not reached (event-inertial: fewer inliers suffice)."""
        if config.mode is SlamMode.EVENT_INERTIAL and config.inertial.min_inliers > 0:
            self._tc_uninit = replace(config.tracking, min_inliers=config.inertial.min_inliers)
        self.calib = calibration
        self.imu = imu if config.mode is SlamMode.EVENT_INERTIAL else None
        self.K = calibration.K
        self.width, self.height = calibration.width, calibration.height
        self._table = calibration.undistortion_table if calibration.model.value != "none" else None
        wcfg = config.window
        if self.imu is not None and config.inertial.configuration is InertialConfiguration.C3:
            # E-I-C3: fixed tiny windows, and no withdrawal of tiny windows by event rate.
            wcfg = replace(wcfg, adapt_events=False, min_event_rate=0.0)
        mcfg = config.mci
        if self.imu is not None:
            mcfg = replace(mcfg, reference_fraction=mcfg.reference_fraction_inertial, use_parallax=mcfg.use_parallax_inertial,
                           unwarped_own_events_before_map=False)  # event-only
        # Tracks carried through the next window cost a KLT pass per tiny frame: only for a hypothesis that uses them.
        carry = mcfg.sim2_whole_window or (mcfg.use_parallax and mcfg.parallax_whole_window)
        self.window = EventWindowSelector(wcfg, config.features, config.image, self.width, self.height, config.seed, carry_tracks=carry)
        self.mci_gen = MciGenerator(mcfg, config.image, self.K, self.width, self.height, config.seed)
        icfg = config.initialization
        self._init_cfg = icfg if self.imu is None else replace(icfg, homography_fit_share=icfg.homography_fit_share_inertial,
                                                                min_parallax_deg=icfg.min_parallax_deg_inertial,
                                                                plane_min_parallax_deg=icfg.plane_min_parallax_deg_inertial)
        """Two-view settings of this run's mode (event-inertial runs keep their own parallax and decomposition choice)."""
        # Event-only maps re-solve their PnP-placed poses on the final points (TrackingConfig.refit_tracked_poses).
        self.atlas = Atlas(refit_K=self.K if self.imu is None and config.tracking.refit_tracked_poses else None,
                           refit_threshold_px=config.tracking.reprojection_threshold_px,
                           interpolate_between_keyframes=config.tracking.refit_keyframe_interpolation,
                           first_pose_span_us=int(round(config.tracking.first_pose_extrapolation_s * 1e6)),
                           young_pose_us=int(round(config.tracking.young_pose_extrapolation_s * 1e6)))
        self.fe = FrontendTracks()
        self.results: list[SlamStepResult] = []
        """One result per processed MCI."""
        self._next_point = 0
        self._state = SlamStatus.NOT_INITIALISED
        self._last_t = 0
        self.last_imu_init = None
        """Outcome of the last IMU initialisation attempt (event-inertial mode)."""
        self.last_scale_refinement = None
        """Outcome of the last scale refinement (``InertialConfig.refine_after_s``)."""
        self._prev_hypothesis: str | None = None
        """Hypothesis of the previous MCI ("H1".."H5")."""
        self._last_visual_t = 0
        """Time of the last MCI tracked visually (C2/C3 bound their IMU bridges by it), us."""
        self._rejoin: RejoinCandidate | None = None
        """The last map lost while coasting (``InertialConfig.rejoin_s``), which the next two-view map may continue."""
        self._blank_us = 0
        """Time the event window rejected for a low event rate since the last MCI tracked visually (``TrackingConfig.coast_blank_s``), us."""
        self._after_blank_t: int | None = None
        """Time of the first MCI after the last blank wall since the last MCI tracked visually (``coast_after_blank_s``), us."""
        self._last_pnp_t = 0
        """Time of the last MCI placed by PnP on point tracks (``EdgeTrackingConfig.max_span_s``), us."""
        self._prev_mci: tuple = (None, 0)
        """The previous MCI (8-bit image, time in us) while the current one is processed (``VisualGyroConfig``)."""
        self._lines = LineMap()
        """Line tracks and 3-D lines of the active map (``SlamConfig.lines``)."""
        self._gap_last_t: int | None = None
        """Time of the newest event taken, us (:mod:`evpose.slam.system_gaps`)."""
        lim = int(round(config.tracking.lose_after_gap_s * 1e6))
        self._imu_holes = imu_holes(self.imu, calibration.time_offset_us, lim) if self.imu is not None and lim > 0 else []
        """Stretches without IMU samples on the camera clock (event-inertial mode); the events in them are not used."""
        self._imu_end_reported = False

    # --------------------------------------------------------------- public
    def step(self, events: EventArray) -> SlamStepResult:
        """Consume a batch of sensor events; returns the result of the last MCI made from them (or, failing that, of a
        pause of the input that ended the map, or the waiting state)."""
        last, paused = None, None
        for part, gap in self._segments(events):
            if gap is not None:
                paused = self._end_at_gap(gap)
            last = self._consume(part)
            if last.mci is not None:
                paused = None
        if last is None:
            last = self._consume(events[:0])
        return paused if paused is not None else last

    def _consume(self, events: EventArray) -> SlamStepResult:
        if len(events):
            self._last_t = int(events.t[-1])
        x = events.x.astype(np.float64)
        y = events.y.astype(np.float64)
        if self._table is not None and len(events):
            # Events are undistorted before use (paper section V); K stays that of the ideal pinhole.
            uv = self._table[events.y.astype(np.intp), events.x.astype(np.intp)]
            x, y = uv[:, 0].astype(np.float64), uv[:, 1].astype(np.float64)
        windows = self.window.push(events.t, x, y, events.p)
        last = None
        for rw in windows:
            last = self._process_window(rw)
            self.results.append(last)
        if last is None:
            m = self.atlas.active
            reason = WINDOW_REASONS[self.window.last_event]
            last = SlamStepResult(self._last_t, SlamStatus.WAITING, reason, map_id=m.id if m else -1, tiny_frame=self.window.last_tiny_image, n_events_window=self.window.n_events)
        else:
            last.mcis = len(windows)
            last.tiny_frame = self.window.last_tiny_image
        return last

    def snapshot(self) -> dict:
        """A deep copy of all mutable state; :meth:`restore` returns the system to it exactly (viewer seeking)."""
        import copy

        return copy.deepcopy({
            "window": self.window.state, "last_tiny": self.window.last_tiny_image, "last_event": self.window.last_event,
            "n_hist": self.window.n_events_history, "atlas": self.atlas, "fe": self.fe, "next_point": self._next_point,
            "state": self._state, "last_t": self._last_t, "imu_init": self.last_imu_init, "n_results": len(self.results),
            "last_visual_t": self._last_visual_t, "prev_hypothesis": self._prev_hypothesis,
            "scale_refinement": self.last_scale_refinement, "rejoin": self._rejoin, "blank_us": self._blank_us,
            "after_blank_t": self._after_blank_t, "last_pnp_t": self._last_pnp_t, "lines": self._lines,
            "gap_last_t": self._gap_last_t, "imu_end_reported": self._imu_end_reported,
            "coast_hold": self._coast_hold, "speed_refusals": self._speed_refusals,
        })

    def restore(self, snap: dict) -> None:
        import copy

        s = copy.deepcopy(snap)
        self.window.state, self.window.last_tiny_image, self.window.last_event = s["window"], s["last_tiny"], s["last_event"]
        self.window.n_events_history = s["n_hist"]
        self.atlas, self.fe, self._next_point = s["atlas"], s["fe"], s["next_point"]
        self._state, self._last_t, self.last_imu_init = s["state"], s["last_t"], s["imu_init"]
        self._last_visual_t = s.get("last_visual_t", 0)
        self._prev_hypothesis = s.get("prev_hypothesis")
        self.last_scale_refinement = s.get("scale_refinement")
        self._rejoin = s.get("rejoin")
        self._blank_us, self._after_blank_t = s.get("blank_us", 0), s.get("after_blank_t")
        self._last_pnp_t = s.get("last_pnp_t", 0)
        self._lines = s.get("lines", LineMap())
        self._gap_last_t, self._imu_end_reported = s.get("gap_last_t"), s.get("imu_end_reported", False)
        self._coast_hold, self._speed_refusals = s.get("coast_hold"), s.get("speed_refusals", 0)
        del self.results[s["n_results"]:]

    # ------------------------------------------------------------- pipeline
    def _prior(self, rw: ReconstructionWindow) -> MotionPrior:
        prior = MotionPrior()
        m = self.atlas.active
        if self._state is SlamStatus.OK and m is not None and len(m.traj_t) >= 2:
            dt = (m.traj_t[-1] - m.traj_t[-2]) / 1e6
            if dt > 0:
                D = invert_pose(m.traj_T[-2]) @ m.traj_T[-1]
                prior.omega = Rotation.from_matrix(D[:3, :3]).as_rotvec() / dt
                prior.velocity = D[:3, 3] / dt
            T_cw = invert_pose(m.traj_T[-1])
            pids = [self.fe.track_to_point[t] for t in self.fe.ids.tolist() if t in self.fe.track_to_point]
            if pids:
                Xw = np.stack([m.points[p].xyz for p in pids if p in m.points] or [np.full(3, np.nan)])
                if self.mci_gen.cfg.use_parallax:  # H5's depth samples: the tracks' map points seen from the last pose
                    prior.point_uv, prior.point_depth = points_in_view(Xw, T_cw, self.K)
                z = Xw @ T_cw[2, :3] + T_cw[2, 3]
                z = z[np.isfinite(z) & (z > 0)]
                prior.map_depth = float(np.median(z)) if z.size else None
        if self.imu is not None:
            # Gyro mean over the window, rotated into the camera frame: the rotation part of H3.
            off = self.calib.time_offset_us
            w = self.imu.time_window(int(rw.t[0]) + off, int(rw.t[-1]) + off + 1)
            if len(w):
                st = m.inertial if m is not None and m.imu_initialised else None
                bias = st.bias_gyro if st is not None else np.zeros(3)
                prior.omega = self.calib.T_cam_imu[:3, :3] @ (w.gyro.mean(axis=0) - bias)
                if prior.velocity is None:
                    prior.velocity = np.zeros(3)
        return prior

    def _track_mci(self, mci: MciResult) -> MciResult:
        """KLT from the previous MCI; returns the MCI actually used (the previous hypothesis's image may replace the sharpest)."""
        fe = self.fe
        fine = use_fine_grid(fe, mci.n_events, mci.image.size, self.cfg.features)
        if fe.prev8 is not None and len(fe.ids):
            if self.cfg.features.klt_birth_anchor_px > 0:
                fe.birth.register(fe.ids, fe.uv, fe.prev8)  # tracks detected or re-found since the last step
            guess = self._gyro_flow(fe.prev_t, mci.t_us, fe.uv)
            min_ncc = self.cfg.features.klt_min_ncc
            new, ok, fine8 = self._klt(mci, mci.hypothesis.value, guess, min_ncc, fine)
            keep = self.cfg.mci.keep_hypothesis_survival
            prev_h = self._prev_hypothesis
            if keep > 0 and prev_h is not None and prev_h != mci.hypothesis.value and prev_h in mci.candidates and ok.sum() < keep * len(ok):
                img = mci.candidates[prev_h]
                alt = replace(mci, image=img, image8=to_uint8(img), hypothesis=Hypothesis(prev_h), t_us=mci.time_of(prev_h))
                new2, ok2, fine2 = self._klt(alt, prev_h, guess, min_ncc, fine)
                if ok2.sum() > ok.sum():
                    mci, new, ok, fine8 = alt, new2, ok2, fine2
            gate = self.cfg.features.klt_first_step_max_residual_px > 0
            if gate:
                first = np.array([t not in fe.stepped for t in fe.ids.tolist()], bool)
                ok &= step_consistent(fe.uv, new, ok, first, self.cfg.features.klt_first_step_max_residual_px)
            fc = self.cfg.features
            if fc.klt_min_support_ratio > 0 and self.imu is None and self._state is SlamStatus.OK:  # event-only, on a map
                ok &= has_support(mci.image, new, fc.support_window_px, fc.klt_min_support_ratio)
            if self.cfg.features.klt_curvature_gain > 0:
                new = fe.remove_curvature_shift(new, ok, mci.t_us, self.cfg.features, self.cfg.window.overlap)
            if fc.klt_birth_anchor_px > 0:
                new, ok = fe.birth.anchor(mci.image8, fe.ids, new, ok, fc)
            if fc.klt_edge_follow_max_ratio > 0:
                new = fe.slide.follow(fe.prev8, fe.ids, fe.uv, new, ok, fc)
            if fc.klt_edge_slide_px > 0:
                ok = fe.slide.step(fe, new, ok, fc)
            fe.ids, fe.uv = fe.ids[ok], new[ok]
            if gate:  # only the gate reads which tracks have stepped: no per-MCI set otherwise
                fe.stepped = set(fe.ids.tolist())
        else:
            fine8 = mci.fine8(mci.hypothesis.value, self.cfg.features) if fine else None
        fe.prev8, fe.prev_t, fe.prev_fine8 = mci.image8, mci.t_us, fine8
        self._prev_hypothesis = mci.hypothesis.value
        return mci

    def _klt(self, mci: MciResult, hypothesis: str, guess: np.ndarray | None, min_ncc: float,
             fine: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """MCI-to-MCI KLT of the tracks into ``mci`` (on the finer grid when ``fine``, :func:`use_fine_grid`, and the
        previous MCI has a fine image); returns (positions, ok, the fine image or None)."""
        fe, fc = self.fe, self.cfg.features
        fine8 = mci.fine8(hypothesis, fc) if fine else None
        if fine8 is not None and fe.prev_fine8 is not None and fe.prev_fine8.shape == fine8.shape:
            return (*track_features_fine(fe.prev_fine8, fine8, fe.uv, fc, guess, min_ncc, fe.prev8, mci.image8), fine8)
        return (*track_features(fe.prev8, mci.image8, fe.uv, fc, guess=guess, min_ncc=min_ncc), fine8)

    def _replenish(self, img8: np.ndarray, img: np.ndarray | None = None, target: int = 0) -> None:
        """Top the tracks up to ``target`` (0: ``FeatureConfig.target_tracks``; more: a denser grid, ``per_cell`` scaled)."""
        fe, fc = self.fe, self.cfg.features
        target = target if target > fc.target_tracks else fc.target_tracks
        if len(fe.ids) >= target:
            return
        if target > fc.target_tracks:
            fc = replace(fc, per_cell=-(-fc.per_cell * target // fc.target_tracks))
        pts = detect_features(img8, fc, existing=fe.uv, max_total=target - len(fe.ids), support=img)
        if len(pts):
            fe.ids = np.concatenate([fe.ids, np.arange(fe.next_id, fe.next_id + len(pts), dtype=np.int64)])
            fe.uv = np.concatenate([fe.uv, pts.astype(np.float32)])
            fe.next_id += len(pts)

    def _process_window(self, rw: ReconstructionWindow) -> SlamStepResult:
        t0, c0 = time.perf_counter(), time.thread_time()
        # What the pose estimate of this MCI saw and why it failed (StepResult.counts, .failure); set by _track_map.
        self._map_tracks, self._inliers, self._failure = -1, -1, SlamFailure.NONE
        mci = self.mci_gen.generate(rw, self._prior(rw), mapped=self._state is SlamStatus.OK)
        self._blank_us += rw.blank_us
        if rw.blank_us:
            self._after_blank_t = mci.t_us
        t1, c1 = time.perf_counter(), time.thread_time()
        self._prev_mci = (self.fe.prev8, self.fe.prev_t)  # the visual gyro's reference: _track_mci moves on from it
        mci = self._track_mci(mci)
        keyframe = False
        if self._state is SlamStatus.OK:
            status, reason, pose, keyframe = self._track_map(mci)
        else:
            status, reason, pose = self._try_initialise(mci)
            self._failure = SlamFailure.INITIALISING
        t2, c2 = time.perf_counter(), time.thread_time()
        self._replenish(mci.image8, mci.image)
        m = self.atlas.active
        fe = self.fe
        has_pt = np.array([t in fe.track_to_point for t in fe.ids.tolist()], bool)
        t3 = time.perf_counter()
        return SlamStepResult(
            t_us=mci.t_us, status=status, reason=reason, pose=pose, map_id=m.id if m else -1,
            failure=SlamFailure.NONE if status is SlamStatus.OK else self._failure,
            mci=mci.image, hypothesis=mci.hypothesis.value, hypothesis_scores=dict(mci.scores),
            features=fe.uv.copy(), feature_ids=fe.ids.copy(), feature_has_point=has_pt, keyframe=keyframe,
            map_points=m.point_array() if m is not None and status is SlamStatus.OK else None,
            n_events_window=self.window.n_events,
            # Wall times, plus this thread's CPU times (immune to other processes on shared cores).
            timings_ms={"mci": (t1 - t0) * 1e3, "tracking": (t2 - t1) * 1e3, "total": (t3 - t0) * 1e3,
                        "mci_cpu": (c1 - c0) * 1e3, "tracking_cpu": (c2 - c1) * 1e3},
            counts={"tracks": int(len(fe.ids)), "map_points": int(len(m.points)) if m else 0, "keyframes": int(len(m.keyframes)) if m else 0,
                    "events": int(mci.n_events), "map_tracks": self._map_tracks, "inliers": self._inliers, "blank_us": int(rw.blank_us)},
        )

    # ------------------------------------------------------------- tracking
    def _pose_tc(self, m: SlamMap):
        return self.cfg.tracking if m is None or m.imu_initialised else self._tc_uninit

    def _track_map(self, mci: MciResult) -> tuple[SlamStatus, str, np.ndarray | None, bool]:
        m, fe = self.atlas.active, self.fe
        tc = self._pose_tc(m)
        guess = constant_velocity_pose(m, mci.t_us)
        R_prior = self._gyro_rotation(m.traj_t[-1], mci.t_us, m.traj_T[-1])
        if R_prior is not None:
            guess = guess.copy()
            guess[:3, :3] = R_prior
        pred = self._imu_prediction(mci.t_us)
        if pred is not None:
            guess = pred  # metric maps: the IMU predicts position as well
        sel = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
        n_refound = 0
        if len(sel) < self.cfg.search.prepass_below:
            n_refound = self._refind(m, mci, guess, self.cfg.search.radius_px)
            sel = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
        self._map_tracks = len(sel)
        if len(sel) < tc.min_inliers:
            self._failure = SlamFailure.STARVED
            return self._bridge_or_lose(mci, f"{len(sel)} tracked map points < {tc.min_inliers}", self._coast_rotation(m, mci, R_prior))
        est, sel = self._estimate(m, mci, sel, guess, R_prior)
        if not est.ok:
            self._failure = SlamFailure.REJECTED
            return self._bridge_or_lose(mci, est.reason, self._coast_rotation(m, mci, R_prior))
        more = self._refind(m, mci, est.T_wc, self.cfg.search.refine_radius_px)
        n_refound += more
        fused = ""
        if self.imu is None and self.cfg.search.fuse_radius_px > 0:
            n_fused = fuse_tracks(m, self.K, est.T_wc, fe.ids, fe.uv, fe.track_to_point, self.cfg.search.fuse_radius_px, mci.image8.shape)
            more, fused = more + n_fused, f", {n_fused} taken over by new tracks"
        if more:
            # Second pass with the estimated pose (ORB-SLAM's local-map search): re-solve with the new associations.
            sel2 = [i for i, t in enumerate(fe.ids.tolist()) if fe.track_to_point.get(t) in m.points]
            est2, sel2 = self._estimate(m, mci, sel2, est.T_wc, R_prior)
            if est2.ok:
                est, sel = est2, sel2
                self._map_tracks = len(sel2)
        jump = self._speed_jump(m, mci.t_us, est.T_wc)
        self._speed_refusals = self._speed_refusals + 1 if jump is not None else 0
        if jump is not None:
            self._failure = SlamFailure.REJECTED
            return self._bridge_or_lose(mci, jump, self._coast_rotation(m, mci, R_prior))
        for k in np.flatnonzero(~est.inliers):
            fe.track_to_point.pop(int(fe.ids[sel[k]]), None)
        inl = [sel[k] for k in np.flatnonzero(est.inliers)]
        T_wc, segs = self._pnp_pose_with_lines(m, mci, est.T_wc, inl)
        self._last_visual_t, self._blank_us, self._after_blank_t = mci.t_us, 0, None
        self._last_pnp_t = mci.t_us
        m.add_pose(mci.t_us, T_wc)
        if m.refit_K is not None:
            rest = np.setdiff1d(np.arange(len(fe.ids)), inl)
            m.record_pose_observations(mci.t_us, np.array([fe.track_to_point[int(fe.ids[i])] for i in inl], np.int64), fe.uv[inl],
                                       fe.ids[rest], fe.uv[rest], est.prior_sigmas)
        n_tracked = self._inliers = int(est.inliers.sum())
        keyframe = False
        if need_keyframe(m, fe.ids, fe.uv, n_tracked, tc, mci.t_us) or (self.imu is None and young_map(m, mci.t_us, tc, T_wc)):
            # Event-only: a keyframe stepping a multiple of the map's keyframe speed would hand a wrong scale on
            # (TrackingConfig.keyframe_step_ratio).
            collapse = keyframe_step_collapse(m.keyframes, mci.t_us, T_wc, n_tracked, tc) if self.imu is None else None
            if collapse is not None:
                return self._lose(collapse)
            keyframe, T_kf = check_keyframe_step(m.keyframes, mci.t_us, T_wc, n_tracked, tc) if self.imu is None else (True, T_wc)
            if keyframe:
                if T_kf is not T_wc:
                    m.add_pose(mci.t_us, T_kf)  # replaces the PnP pose just added
                T_wc = self._new_keyframe(m, mci.t_us, T_kf, mci.image8)
        self._lines_after_pose(m, mci, T_wc, segs)
        return SlamStatus.OK, f"{n_tracked} inliers ({n_refound} re-found by projection{fused}), rms {est.rms_px:.2f} px", T_wc.copy(), keyframe

    _speed_refusals = 0
    """PnP poses refused in a row by ``TrackingConfig.speed_jump_ratio``."""

    def _estimate(self, m: SlamMap, mci: MciResult, sel: list[int], guess: np.ndarray, R_prior: np.ndarray | None) -> tuple[PoseEstimate, list[int]]:
        """Pose from the map points of the tracks ``sel`` (indices into the frontend's tracks), gyro-refined when a prior exists."""
        fe = self.fe
        Xw = np.stack([m.points[fe.track_to_point[int(fe.ids[i])]].xyz for i in sel])
        uv = fe.uv[sel].astype(np.float64)
        est = estimate_pose(self.K, Xw, uv, guess, self._pose_tc(m), self.cfg.seed)
        if est.ok and self.imu is None and self.cfg.tracking.pnp_motion_prior_ratio > 0:
            est = self._motion_prior_pose(m, mci.t_us, est, Xw, uv)
        sigma_deg = self.cfg.inertial.gyro_prior_deg if m.imu_initialised else self.cfg.inertial.gyro_prior_uninit_deg
        if est.ok and R_prior is not None and sigma_deg > 0:
            est = self._refine_with_gyro(est, Xw, uv, R_prior, sigma_deg)
        max_jump = self._pose_tc(m).max_jump_depths
        if est.ok and max_jump > 0:
            # Between two MCIs (milliseconds) the camera cannot move a multiple of the scene depth: a pose that far from
            # both the prediction and the last pose fits a wrong subset of the map (TrackingConfig.max_jump_depths).
            jump = pose_jump_depths(est.T_wc, (m.traj_T[-1], guess), Xw)
            if jump > max_jump:
                est = PoseEstimate(False, reason=f"PnP pose {jump:.1f} median point depths from the last and the predicted pose > {max_jump:g}")
        return est, sel

    def _new_keyframe(self, m: SlamMap, t_us: int, T_wc: np.ndarray, img8: np.ndarray | None = None, adjust: bool = True,
                      triangulate: bool = True) -> np.ndarray:
        """Insert a keyframe, triangulate, run local (inertial) BA, cull, try the IMU initialisation; returns the adjusted pose."""
        fe, tc = self.fe, self.cfg.tracking
        kf = insert_keyframe(m, t_us, T_wc, fe.ids, fe.uv.astype(np.float64), fe.track_to_point)
        kf.visual = t_us == self._last_pnp_t  # coasted / IMU-predicted keyframes are not (InertialConfig.init_visual)
        self._measure_room(kf, img8)
        if triangulate:
            tt = young_triangulation(tc) if self.imu is None and young_map(m, t_us, tc, T_wc) else tc  # feed a young map
            self._next_point = triangulate_new_points(m, self.K, kf, fe.track_to_point, tt, self._next_point,
                                                      # event-only coasts: event-inertial maps bridge on the IMU
                                                      predicted=self.imu is None and t_us != self._last_pnp_t)
            if self.imu is None:
                check_new_points(m, kf, fe.track_to_point, tt)  # off by default (evpose.slam.keyframe_scale)
        if img8 is not None:
            store_patches(m, kf.id, img8, self.cfg.search.patch_px)
            if self._matcher() is SearchMatcher.KLT:
                keep_keyframe_image(m, kf, img8, tc.local_window)
        ic = self.cfg.inertial
        before = keyframe_positions(m) if adjust and self.imu is not None and ic.carry_mci_scale else None
        if not adjust:
            pass
        elif m.imu_initialised and ic.inertial_ba:
            inertial_local_bundle_adjustment(m, m.inertial, self.K, self.imu, self.calib.T_cam_imu, self.calib.time_offset_us,
                                             tc.local_window, tc.ba_iterations, tc.ba_huber_px, ic.acc_noise, ic.gyro_noise,
                                             ic.acc_bias_sigma, ic.gyro_bias_sigma, ic.velocity_from_imu,
                                             velocity_prior_sigma=ic.ba_velocity_prior_sigma, min_span_s=ic.ba_min_span_s, span_keyframes=ic.ba_span_keyframes,
                                             anchors=ic.ba_window)
        else:
            priors = self._keyframe_rotation_priors(m)
            sigma, pair_sigmas = self._ba_rotation_sigmas(m, priors)
            # A re-joined map's older segment shares no points with the newest one (SlamMap.segment_start_kf).
            window, n_fixed = visual_ba_window(m, tc, event_only=self.imu is None)
            if self.imu is not None and ic.ba_gyro_prior_chain:
                window = anchored_window(m, window)  # its fixed keyframe must be one the BA holds
            # InertialConfig.rejoin_scale_anchor: a young re-joined segment keeps the scale the re-join gave it.
            anchor = tc.ba_scale_anchor if self.imu is None else (ic.rejoin_scale_anchor if starts_at_rejoin(m, window) else 0.0)
            local_bundle_adjustment(m, self.K, window, tc.ba_iterations, tc.ba_huber_px, n_fixed=n_fixed,
                                    rotation_priors=priors, rotation_sigma_rad=sigma, rotation_sigmas_rad=pair_sigmas,
                                    # Event-inertial maps get their scale from the IMU initialisation; anchoring the visual
                                    # scale before it made E-I-C2 worse (TrackingConfig.ba_scale_anchor).
                                    scale_anchor=anchor,
                                    velocity_sigma_ratio=tc.ba_velocity_prior if self.imu is None else 0.0,
                                    rotation_rate_sigma_rad_s=np.radians(tc.ba_rotation_rate_prior_deg_s) if self.imu is None else 0.0,
                                    edge_along_sigma_px=tc.ba_edge_along_sigma_px if self.imu is None else 0.0,
                                    edge_max_ratio=tc.ba_edge_max_ratio, max_jump_depths=tc.max_jump_depths,
                                    attitude_priors=self._room_priors(m, window),
                                    extra_factors=speed_factor_hook(m, self.cfg.young_scale, t_us) if self.imu is None else None)
        if before is not None:
            carry_relative_scale(m, before)
        cull_points(m, self.K, fe.track_to_point, tc, min_depth_ratio=tc.cull_min_depth_ratio if self.imu is None else 0.0)
        if self.imu is None and adjust:
            maybe_restructure(m, self.K, self.cfg.restructure, self._init_cfg, tc, fe.track_to_point, self.cfg.seed)
        # BA moved the newest keyframe: the trajectory's last pose follows it.
        m.add_pose(t_us, m.keyframes[-1].T_wc)
        if self.imu is not None and (m.imu_initialised or self.cfg.inertial.reanchor_before_init) and len(m.keyframes) >= 2:
            # The MCIs between the previous keyframe and this one are complete: their rotations follow the gyro.
            self._reanchor_rotations(m, {m.keyframes[-2].id})
        if self.imu is not None and not m.imu_initialised:
            self._try_imu_init(m)
        elif self.imu is not None and not m.scale_refined and ic.refine_after_s > 0 and (t_us - m.imu_init_t_us) / 1e6 >= ic.refine_after_s:
            self._refine_scale(m)
        return m.keyframes[-1].T_wc
