"""The steppable tracking engine: front end (filter, SP-TS, TDF) + visible map + registration, one update per ``step``.

``Tracker.step(until_t_us, events)`` consumes the events the caller hands it
(those since the previous step, time-sorted), updates the front end, predicts
the pose, culls the map, builds the TDF around the projected map and registers.
The full state (filter and SP-TS maps, predictor, pose, clock) is copied by
``snapshot()`` and put back by ``restore()``; everything is deterministic, so a
restored tracker fed the same events reproduces the same results bit for bit.

Plug-in points for fusion (issue 7): ``predictor`` (any :class:`MotionPredictor`,
e.g. IMU-driven) and ``polarity_selector`` (per used map point +1 / -1 / 0 for
the TDF it is evaluated on). ``stpe`` mode uses a constant-velocity Kalman filter
(:mod:`evpose.tracker.motion_filter`: each registration is fused with its
covariance instead of copied into the track; ``motion_model`` picks it; its
predicted covariance is also the registration's pose prior, scaled by
``motion_filter.prior_residual_sigma``) and the combined-polarity TDF.
"""

from __future__ import annotations

import dataclasses

import time
from typing import Callable

import gtsam
import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.errors import InputError
from evpose.frontend.distance_field import TemporalDistanceField
from evpose.frontend.noise_filter import ConsistencyNoiseFilter
from evpose.frontend.time_surface import SeparatedTimeSurface
from evpose.fusion import aligned_field
from evpose.fusion.aligned_surface import AlignedTimeSurface
from evpose.tracker.chance_level import chance_counts
from evpose.tracker.config import MotionModel, TrackerConfig
from evpose.tracker.ego_motion_events import ego_motion_keep, empty_ego_history
from evpose.tracker.anchored_rims import AnchoredRims
from evpose.tracker.edge_offsets import EdgeOffsetLearner
from evpose.tracker.event_registration import event_registration_for
from evpose.tracker.grazing import add_crease_off_trail, add_grazing_off_trail, crease_points
from evpose.tracker.map_learning import learn_map_points
from evpose.tracker.map_refinement import PaintedEdgeRefiner
from evpose.tracker.motion_filter import ConstantVelocityKalman
from evpose.tracker.point_selection import registered_points
from evpose.tracker.polarity_stage import align_to_polarity, learn_polarity_signs
from evpose.tracker.predictor import ConstantVelocityPredictor, MotionPredictor
from evpose.tracker.reacquisition import Reacquisition
from evpose.tracker.registration import polarity_trail, register_to_map
from evpose.tracker.registration_config import prior_widening
from evpose.tracker.step_result import StepResult, TrackStatus, elapsed_ms, step_debug
from evpose.tracker.stpe_pose import stpe_pose
from evpose.tracker.track_hold import ACQUIRE_UPDATES, TrackHold  # noqa: F401 (ACQUIRE_UPDATES re-exported)
from evpose.tracker.modes import MotionComponents, unfused_predictor
from evpose.tracker.visible_map import VisibleMap, field_box, visible_points
from evpose.tracker.wall_occlusion import wall_foot_mask

PolaritySelector = Callable[[np.ndarray, int, np.ndarray], "np.ndarray | None"]
"""``(T_world_cam_predicted, t_us, map_point_indices) -> int8 polarity per point (+1/-1/0) or None (all combined)``."""


_NO_PRIOR = np.zeros((6, 6))
"""Information matrix of "no prior" for :func:`register_to_map`."""


class Tracker:
    """EV-Pose STPE engine over one contour map and one calibrated camera."""

    def __init__(
        self,
        config: TrackerConfig,
        contour_map: ContourMap,
        calibration: CameraCalibration | None,
        predictor: MotionPredictor | None = None,
        polarity_selector: PolaritySelector | None = None,
        components: MotionComponents | None = None,
    ):
        """``components`` (from :func:`~evpose.tracker.modes.build_motion_components`) add the IMU fusion,
        polarity filter and ego-motion filter of the fused modes; explicit ``predictor`` /
        ``polarity_selector`` arguments take precedence over them."""
        if calibration is None:
            raise InputError(None, "the recording has no camera calibration; tracking needs intrinsics")
        if contour_map is None or len(contour_map) == 0:
            raise InputError(None, "the map has no points")
        if not np.all(np.isfinite(contour_map.points)):
            raise InputError(None, "the map has NaN or infinite coordinates")
        self.config = config
        self.map = contour_map
        self.calibration = calibration
        self.K = calibration.K
        w, h = calibration.width, calibration.height
        self.width, self.height = w, h
        self._points = np.array(contour_map.points, dtype=np.float64, order="C")
        """The points registration reads (a copy: the painted-edge refiner moves some of them)."""
        self.visible_map = VisibleMap(contour_map.points, self.K, w, h)
        self._tangents = np.ascontiguousarray(np.cross(contour_map.plane_normal, contour_map.edge_normal), dtype=np.float64)
        """Unit edge direction per map point (zero where the map does not know it), for the crowding test."""
        self.noise_filter = ConsistencyNoiseFilter(config.noise_filter, w, h)
        self.time_surface = SeparatedTimeSurface(config.time_surface, w, h, calibration)
        self.distance_field = TemporalDistanceField(config.distance_field, w, h)
        coarse = int(config.distance_field.coarse_blur_px)
        self.coarse_field = TemporalDistanceField(config.distance_field.level(coarse), w, h) if coarse > 0 else None
        """Optional coarser field registered first (coarse-to-fine), None when ``coarse_blur_px`` is 0."""
        self.components = components if components is not None else MotionComponents()
        mr = config.map_refinement
        if self.components.drives_pose and float(mr.fused_gain) > 0:  # the fused modes' own gain (see its docstring)
            mr = dataclasses.replace(mr, gain=float(mr.fused_gain))
        self.refiner = (PaintedEdgeRefiner(mr, contour_map)
                        if mr.enabled and (mr.fused_modes or not self.components.drives_pose) else None)
        """Online refinement of the map's painted edges (None when off, or in the fused modes unless asked for)."""
        rc = config.registration
        self._registration = (dataclasses.replace(rc, min_inlier_ratio=rc.fused_min_inlier_ratio, lag_floor_px=rc.fused_lag_floor_px)
                              if self.components.drives_pose else rc)
        """The registration settings this tracker's mode uses (the fused modes' own inlier test)."""
        widen = prior_widening(rc, 1e3 / float(self.K[0, 0])) if self.components.drives_pose else 1.0
        if widen != 1.0:
            self._registration = dataclasses.replace(self._registration, prior_rotation_deg=rc.prior_rotation_deg * widen,
                                                     prior_translation_m=rc.prior_translation_m * widen)
        self._weak_test = (not self.components.drives_pose and config.motion_model is MotionModel.KALMAN and predictor is None
                           and 0.0 < float(rc.weak_inlier_ratio) < float(rc.min_inlier_ratio))
        """``stpe`` with the Kalman filter: registrations between ``weak_inlier_ratio`` and ``min_inlier_ratio`` are
        judged by their agreement with the motion prediction instead of being a lost track."""
        if self._weak_test:
            self._registration = dataclasses.replace(rc, min_inlier_ratio=rc.weak_inlier_ratio)
        self._normal_only = (not self.components.drives_pose and float(rc.normal_gradient_min_pixel_mrad) > 0
                             and 1e3 / float(self.K[0, 0]) >= float(rc.normal_gradient_min_pixel_mrad))
        """Registration reads the field along the points' edge normals only (``normal_gradient_min_pixel_mrad``)."""
        vm = config.visible_map
        self._wall_feet = (wall_foot_mask(contour_map, vm.wall_inward_m, vm.wall_radius_m, vm.wall_min_height_m, vm.wall_max_height_m)
                           if (vm.fused_wall_occlusion if self.components.drives_pose else vm.wall_occlusion) else None)
        """Map points at the foot of a wall (:mod:`evpose.tracker.wall_occlusion`), None when off for this mode."""
        self._edge_normals = np.ascontiguousarray(contour_map.edge_normal, dtype=np.float64)
        self._hold_filtered = not self.components.drives_pose and mr.hold_out_filtered
        """``stpe+filter`` holds unrefined painted points out of registration too (``map_refinement.hold_out_filtered``)."""
        self.hold = TrackHold(not self.components.drives_pose or self._registration is rc, rc.regain_updates,
                               rc.weak_run_degraded_updates)
        """The fused modes' looser inlier test applies only once the map is acquired (``ACQUIRE_UPDATES`` strict
        registrations in a row); ``stpe`` regains a lost track only after ``regain_updates`` of them."""
        if predictor is None and self.components.drives_pose:
            predictor = self.components.motion
        if polarity_selector is None:
            polarity_selector = self.components.polarity_selector
        self.predictor = predictor if predictor is not None else unfused_predictor(config)
        self.polarity_selector = polarity_selector
        eo = config.edge_offsets
        for_mode = eo.full if self.components.drives_pose else eo.stpe_filter if polarity_selector is not None else True
        self.edge_offsets = (EdgeOffsetLearner(eo, self._points, contour_map.edge_normal, self._tangents,
                                               None if self.refiner is None else self._painted_mask())
                             if eo.enabled and for_mode and 1e3 / float(self.K[0, 0]) >= float(eo.min_pixel_mrad) else None)
        """Gauge-free online offsets of the registered points (:mod:`evpose.tracker.edge_offsets`; every mode has its
        own switch and lag; coarse sensors only), None when off or when the map knows no point's edge direction (its lag
        then stays the config's)."""
        if self.edge_offsets is not None and self.edge_offsets.owned == 0:
            self.edge_offsets = None
        ar = eo.anchored_rims
        self.anchored_rims = (AnchoredRims(ar, contour_map, float(config.map_refinement.max_curvature), self.edge_offsets,
                                           None if self.refiner is None else self._painted_mask())
                              if self.edge_offsets is not None and ar.anchor_share > 0 else None)
        """The rims' absolute refinement while other edges anchor (:mod:`evpose.tracker.anchored_rims`), None when off."""
        lag_ms = float(eo.full_field_lag_ms if self.components.drives_pose
                       else eo.stpe_filter_field_lag_ms if polarity_selector is not None else eo.field_lag_ms)
        if self.edge_offsets is not None and lag_ms > 0:
            self._registration = dataclasses.replace(self._registration, field_lag_ms=lag_ms)
        self.event_registration = (event_registration_for(config, contour_map, self._tangents, w, h, 1e3 / float(self.K[0, 0]))
                                   if config.event_registration.enabled and self.components.drives_pose else None)
        """The fused modes' registration of the step's events at their own timestamps
        (:mod:`evpose.tracker.event_registration`), None when off."""
        self._crease = (crease_points(contour_map.points, contour_map.plane_normal, contour_map.region_id,
                                      float(config.event_registration.crease_radius_m))
                        if float(config.registration.fused_crease_off_trail_px) != 0 else None)
        self._pose: np.ndarray | None = None
        self._t_us: int | None = None
        self._steps = 0
        self.chance_until_us: int | None = None
        """Updates up to this time (microseconds) also count the chance level of their inlier share
        (:mod:`evpose.tracker.chance_level`), None = none do: the acquisition window asks for it."""
        self._ego_history = empty_ego_history()
        """Recent noise-filtered events (ideal x, y, t us) the ego-motion filter judges new ones against."""
        self.reacquisition = Reacquisition(config.reacquisition) if config.reacquisition.enabled else None
        """The search for the pose after a restart without one (:mod:`evpose.tracker.reacquisition`); while it is
        :attr:`~evpose.tracker.reacquisition.Reacquisition.active`, :meth:`step` runs it instead. None when off."""

    # ------------------------------------------------------------------ state
    @property
    def pose(self) -> np.ndarray | None:
        """Current ``T_world_cam`` estimate (4, 4), None before :meth:`start`."""
        return None if self._pose is None else self._pose.copy()

    @property
    def t_us(self) -> int | None:
        return self._t_us

    def visible_count(self, T_world_cam: np.ndarray) -> int:
        """How many map points survive culling at a pose (to check an initial pose before tracking)."""
        return int(visible_points(self._points, T_world_cam, self.K, self.width, self.height, self.config.visible_map).size)

    def feed(self, events: EventArray) -> np.ndarray:
        """Push events through the noise filter into the SP-TS without a pose update; returns the keep-mask."""
        keep = self.noise_filter.filter(events)
        self.time_surface.update(events, keep)
        return keep

    def start(self, T_world_cam: np.ndarray, t_us: int) -> int:
        """Set the initial pose at ``t_us``; returns the number of map points visible from it."""
        T = np.asarray(T_world_cam, dtype=np.float64).reshape(4, 4)
        if not np.all(np.isfinite(T)):
            raise InputError(None, "the initial pose has NaN or infinite values")
        self._pose = T.copy()
        self._t_us = int(t_us)
        self._ego_history = empty_ego_history()  # a restart after an event gap: those events are long past
        self.hold.start()
        self.predictor.reset(int(t_us), T)
        if self._side_motion() is not None:
            self._side_motion().reset(int(t_us), T)
        return self.visible_count(T)

    def _stateful(self) -> dict:
        """The components with their own ``snapshot``/``restore``, by state key, in restore order (None: absent)."""
        return {"noise_filter": self.noise_filter, "time_surface": self.time_surface, "predictor": self.predictor,
                "motion": self._side_motion(),
                "selector": self.polarity_selector if hasattr(self.polarity_selector, "snapshot") else None,
                "visible_map": self.visible_map, "map_refinement": self.refiner,
                "anchored_rims": self.anchored_rims, "edge_offsets": self.edge_offsets,
                "event_registration": self.event_registration}

    def snapshot(self) -> dict:
        """Deep copy of the full engine state.

        Arrays are copied with ``np.copy`` (keeps the memory layout): gtsam hands out column-major matrices, and a
        C-ordered copy takes another BLAS path in later products, so a restored run would drift from the
        uninterrupted one at the rounding level (seen with numpy 2.4).
        """
        state = {key: None if c is None else c.snapshot() for key, c in self._stateful().items()}
        state["acquisition"], state["tracking"] = self.hold.snapshot()
        state.update(pose=None if self._pose is None else np.copy(self._pose), t_us=self._t_us, steps=self._steps,
                     ego_history=tuple(np.copy(a) for a in self._ego_history))
        if self.reacquisition is not None:
            state["reacquisition"] = self.reacquisition.snapshot()
        return state

    def restore(self, state: dict) -> None:
        for key, c in self._stateful().items():
            if c is not None and state.get(key) is not None:
                c.restore(state[key])
                if key in ("map_refinement", "edge_offsets"):
                    c.apply(self._points)  # the map's points carry what they learned
        self._pose = None if state["pose"] is None else np.copy(state["pose"])
        self._t_us = state["t_us"]
        self._steps = state["steps"]
        self._ego_history = tuple(np.copy(a) for a in state["ego_history"])
        self.hold.restore(state["acquisition"], state.get("tracking", (True, 0, True)))
        if self.reacquisition is not None:
            self.reacquisition.restore(state.get("reacquisition"))  # None (idle) too: a search restored over stops

    def _side_motion(self):
        """The fusion backend when it runs beside (not as) the predictor, as in ``stpe+filter``."""
        motion = self.components.motion
        return motion if motion is not None and motion is not self.predictor else None

    # ------------------------------------------------------------------- step
    def step(self, until_t_us: int, events: EventArray, imu: ImuSamples | None = None, debug: bool = False) -> StepResult:
        """Consume ``events`` (those up to ``until_t_us``), update the pose at ``until_t_us``.

        ``imu`` holds the IMU samples since the previous step (IMU clock); ``stpe`` mode ignores it,
        the fused modes feed it to the fusion backend before predicting.
        """
        if self.reacquisition is not None and self.reacquisition.active:
            return self.reacquisition.step(self, int(until_t_us), events, imu)
        return self.track(until_t_us, events, imu, debug)

    def track(self, until_t_us: int, events: EventArray, imu: ImuSamples | None = None, debug: bool = False) -> StepResult:
        """:meth:`step` without the re-acquisition search (which runs its pose hypotheses through this)."""
        until = int(until_t_us)
        timings: dict[str, float] = {}
        t_total = time.perf_counter()
        # CPU time of this thread too: on the shared machine wall time includes waiting for a core.
        cpu_total = time.thread_time()
        motion = self.components.motion
        if motion is not None and imu is not None and len(imu):
            motion.fusion.add_imu(imu)

        t0 = time.perf_counter()
        keep = self.noise_filter.filter(events)
        timings["noise_filter"] = elapsed_ms(t0)
        ego = self.components.ego_motion
        n_ego_removed = 0
        if ego is not None and self._pose is not None and len(events):
            t0 = time.perf_counter()
            keep_ego, self._ego_history = ego_motion_keep(self.components, self.calibration, self._points,
                                                          self._ego_history, events, keep, until)
            n_ego_removed = int(np.count_nonzero(keep & ~keep_ego))
            keep &= keep_ego
            timings["ego_motion"] = elapsed_ms(t0)
        t0 = time.perf_counter()
        self.time_surface.update(events, keep)
        timings["time_surface"] = elapsed_ms(t0)
        n_in = len(events)
        n_kept = int(np.count_nonzero(keep))
        counts = {"events_in": n_in, "events_kept": n_kept}
        if ego is not None:
            counts["events_ego_removed"] = n_ego_removed
        self._steps += 1

        if self._pose is None:
            self._t_us = until
            timings["total"] = elapsed_ms(t_total)
            timings["total_cpu"] = (time.thread_time() - cpu_total) * 1e3
            return StepResult(until, np.full((4, 4), np.nan), TrackStatus.NOT_INITIALISED, "no initial pose", timings_ms=timings, counts=counts)

        predicted = self.predictor.predict(until)
        t0 = time.perf_counter()
        visible, used, pts, used_tangents, skip = registered_points(self, predicted)
        roi = self._field_box(pts, predicted)
        timings["culling"] = elapsed_ms(t0)
        counts.update(points_visible=int(visible.size), points_used=int(used.size))

        t0 = time.perf_counter()
        polarity = None if self.polarity_selector is None else self.polarity_selector(predicted, until, used)
        if self.polarity_selector is not None:
            # Per part of the filter: prediction (includes the fusion's IMU propagation to ``until``, which its update
            # then reuses), T_align composition, and the labelling after registration (below).
            timings["polarity_predict"] = elapsed_ms(t0)
        # --- polarity event filter (issue 7, evpose/tracker/polarity_stage.py): registration reads T_align, one field.
        surface, field_polarity = self.time_surface, polarity
        composed = used, polarity  # what T_align is composed for: labelling and sign learning take them all
        if polarity is not None and hasattr(self.polarity_selector, "align"):
            t1 = time.perf_counter()
            aligned, with_events = align_to_polarity(self, used, pts, polarity, skip, predicted, roi, events, keep, until, counts)
            if aligned is not None:
                surface, field_polarity = aligned, None
                if with_events is not None:
                    # Points whose patch shows no recent event of their polarity cannot pull the pose, and held-out
                    # painted points must not yet: skip them.
                    used, pts, polarity = used[with_events], pts[with_events], polarity[with_events]
                    used_tangents = None
                counts["points_registered"] = int(used.size)
            timings["polarity_align"] = elapsed_ms(t1)
        # --- end polarity event filter
        if self.polarity_selector is not None:
            timings["polarity_filter"] = elapsed_ms(t0)
        t0 = time.perf_counter()
        pols = (0,) if field_polarity is None else tuple(sorted({int(p) for p in np.unique(field_polarity)}))
        # Registration takes the curvature from the field's values (bit for bit the same): no curvature images.
        curv = False
        if isinstance(surface, AlignedTimeSurface):  # issue 7: T_align's field from its patch pixels, same values
            aligned_field.fill_distance_field(surface, self.distance_field, until, roi, curv)
        else:
            self.distance_field.compute(surface, until, pols, roi, curv)
        levels = [self.distance_field]
        if self.coarse_field is not None:
            self.coarse_field.compute(surface, until, pols, self._field_box(pts, predicted, True), curv)
            levels.insert(0, self.coarse_field)
        timings["distance_field"] = elapsed_ms(t0)

        t0 = time.perf_counter()
        weak = False
        twist = None
        trail = None
        if used.size < self.config.registration.min_points:
            reg = None
            reason = f"only {visible.size} map points in view at the predicted pose (need {self.config.registration.min_points})"
        else:
            # The TDF's minimum trails moving edges; registration compensates with the camera's twist.
            dt_s = (until - self._t_us) * 1e-6
            if isinstance(self.predictor, (ConstantVelocityPredictor, ConstantVelocityKalman)):
                # Its fitted twist: the prediction also carries a smoothing correction of the last pose, not motion.
                twist = self.predictor.twist()
            else:
                twist = gtsam.Pose3(mat=self._pose).logmap(gtsam.Pose3(mat=predicted)) / dt_s if dt_s > 0 else None
            prior_info = None
            if isinstance(self.predictor, ConstantVelocityKalman):
                # The filter fuses the prediction itself; the registration's isotropic prior would count it twice
                # (all-zero information = no prior), unless the filter's own covariance is asked to act as the prior.
                prior_info = self.predictor.prior_information(until) if self.config.motion_filter.prior_in_registration else _NO_PRIOR
            split = float(self.config.registration.fused_polarity_trail_px)
            both = float(self.config.registration.fused_buffer_trail_px)
            if (split != 0 or both != 0) and self.components.drives_pose and polarity is not None:
                # OFF points' fields trail further than ON points' (``fused_polarity_trail_px``), those of points shown
                # both polarities further still (``fused_buffer_trail_px``), OFF ones of grazing surfaces too.
                trail = polarity_trail(polarity, 0.5 * split, -0.5 * split, both)
                add_grazing_off_trail(trail, polarity, self.map.plane_normal, used, pts, predicted[:3, 3], self.config)
                add_crease_off_trail(trail, polarity, self._crease, self.map.plane_normal, used, pts, predicted[:3, 3], self.config)
            with_tangents = self._registration.lag_floor_px > 0 or trail is not None or self._normal_only
            tangents = ((used_tangents if used_tangents is not None else np.take(self._tangents, used, axis=0))
                        if with_tangents else None)
            reg = register_to_map(levels, pts, predicted, self.K, self._registration, field_polarity, twist_per_s=twist,
                                  prior_information=prior_info, prior_residual_sigma=self.config.motion_filter.prior_residual_sigma,
                                  tangents_world=tangents, trail_offsets_px=trail, normal_only=self._normal_only)
            if self.polarity_selector is not None and hasattr(self.polarity_selector, "registration_covariance"):
                # Points the polarity filter dropped (no events in their patch) still count in the residual variance.
                reg.covariance = self.polarity_selector.registration_covariance(reg, self._registration)
            if self.event_registration is not None and reg.success:
                t1 = time.perf_counter()
                counts["events_registered"] = int(self.event_registration.refine_registration(
                    reg, used, polarity, events, keep, until, twist, self.K, self.calibration, predicted,
                    self._registration)) * self.event_registration.last_events
                timings["event_registration"] = elapsed_ms(t1)
            reason = reg.reason
            if self._weak_test and reg.success and reg.inliers < float(self.config.registration.min_inlier_ratio) * reg.points_used:
                weak = True
                if not (self.hold.tracking and self.hold.never_lost):
                    # A coasted prediction has a wide covariance that would let a wrong lock through, and a regained
                    # track may be one the strict test cannot tell from a right one (indoor demo: held 0.3-0.45 m and
                    # 19-97 deg off by weak registrations): after a loss only strict registrations count.
                    reg.success = False
                    reason = (f"only {reg.inliers} of {reg.points_used} map points lie on recent events (need "
                              f"{self.config.registration.min_inlier_ratio:g} of them once the track was lost)")
            if not self.hold.acquired and reg.success:
                reason = self.hold.acquisition_test(reg.inliers, reg.points_used, self.config.registration.min_inlier_ratio)
        timings["registration"] = elapsed_ms(t0)

        ok = reg is not None and reg.success and not reason
        fused = None
        covariance = None if not ok else reg.covariance
        if motion is not None:
            t0 = time.perf_counter()
            fused = motion.report(until, reg.T_world_cam if ok else None, reg.covariance if ok else None)
            timings["fusion"] = elapsed_ms(t0)
        t_prev = self._t_us
        if self.components.drives_pose:
            # Fused output: a failed registration is bridged by IMU propagation (degraded), never dropped.
            self._pose = fused.T_world_cam.copy()
            if fused.readout_T_world_cam is not None and motion.fusion.config.revision_readout_prior:
                self._pose = fused.readout_T_world_cam.copy()  # FusionConfig.revision_readout_prior: a closed loop
            covariance = fused.covariance
            status = TrackStatus.OK if ok and not fused.degraded else TrackStatus.DEGRADED
            if status is TrackStatus.DEGRADED and ok:
                reason = "IMU dead reckoning: the fusion backend ignores registrations"
        else:
            # Registrations are measurements (Kalman filter) or copied into the track: see evpose.tracker.stpe_pose.
            self._pose, status, reason, kalman_cov = stpe_pose(self.predictor, self.config.motion_filter, until, reg, ok, weak,
                                                               predicted, reason)
            if kalman_cov is not None:
                covariance = kalman_cov
        self._t_us = until
        if self._weak_test:
            status, reason = self.hold.regain(status, reason, ok and not weak)
        if status is TrackStatus.LOST:
            self.hold.never_lost = False
        learn_map_points(self, status, used, field_polarity, levels, twist, trail, counts, timings)
        if self.polarity_selector is not None and hasattr(self.polarity_selector, "observe") and polarity is not None:
            learn_polarity_signs(self, events, keep, composed, polarity, surface, counts, timings)
        counts["registered"] = int(ok)
        if self._weak_test:
            status, reason = self.hold.weak_run(status, reason, ok and weak)
            counts["weak_run"] = self.hold.weak_streak
        if reg is not None:
            counts.update(inliers=reg.inliers, iterations=reg.iterations, points_in_image=reg.points_used)
            if self.chance_until_us is not None and until <= self.chance_until_us:
                counts.update(chance_counts(levels[-1], reg.uv, field_polarity, self._registration.inlier_threshold))
        else:
            counts.update(inliers=0, iterations=0, points_in_image=0)
        timings["total"] = elapsed_ms(t_total)
        timings["total_cpu"] = (time.thread_time() - cpu_total) * 1e3

        result = StepResult(
            t_us=until,
            pose=self._written_pose(fused),
            status=status,
            reason="" if status is TrackStatus.OK else reason,
            registration_pose=None if reg is None else reg.T_world_cam.copy(),
            covariance=covariance,
            velocity=None if fused is None else fused.velocity_world.copy(),
            timings_ms=timings,
            counts=counts,
        )
        if debug and motion is not None and t_prev is not None:
            result.imu_poses = motion.fusion.imu_rate_poses(t_prev, until)
        if debug:
            result.debug = step_debug(self.time_surface, self.distance_field, until, events, keep, visible, used, reg, polarity)
        return result

    # ---------------------------------------------------------------- helpers
    def _written_pose(self, fused) -> np.ndarray:
        """The step's output pose: the fused pose, or its read-out (``FusionConfig.revision_readout_states``), which
        is only written, never used by the tracker itself."""
        if self.components.drives_pose and fused is not None and fused.readout_T_world_cam is not None:
            return fused.readout_T_world_cam.copy()
        return self._pose.copy()

    def _painted_mask(self) -> np.ndarray:
        """(N,) bool over the map: the points the painted-edge refiner owns (built once; do not write)."""
        if getattr(self, "_painted", None) is None:
            self._painted = np.zeros(self._points.shape[0], dtype=np.bool_)
            self._painted[self.refiner.index] = True
        return self._painted

    def _field_box(self, pts: np.ndarray, T_world_cam: np.ndarray, coarse: bool = False) -> tuple[int, int, int, int] | None:
        """The rows/columns of the field this update needs (:func:`~evpose.tracker.visible_map.field_box`)."""
        blur = int(self.config.distance_field.coarse_blur_px if coarse else self.config.distance_field.blur_px)
        return field_box(pts, T_world_cam, self.K, int(self.config.field_margin_px) + blur, self.width, self.height)
