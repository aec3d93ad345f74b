"""The tracker's ``polarity_selector`` in the fused modes: :class:`MapPolaritySelector` drives polarity prediction
(:class:`~evpose.fusion.polarity.PolarityPredictor`) from a fusion backend's motion, composes ``T_align``
(:mod:`evpose.fusion.aligned_surface`) and labels the step's events for sign learning.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from evpose.fusion.event_labels import classify_events, filter_summary, observed_point_polarity

if TYPE_CHECKING:
    from evpose.fusion.polarity import PolarityPredictor


class MapPolaritySelector:
    """Adapter to the tracker's ``polarity_selector`` hook: ``(T_world_cam, t_us, map_indices) -> int8``.

    ``motion`` is any fusion backend (its ``predict(t_us)`` gives the bias-corrected
    angular rate and the fused velocity). After registration, :meth:`observe`
    classifies the step's events against the prediction (kept / removed /
    outside patches, for reports and the viewer) and feeds sign learning.
    Counts of the last call are kept in ``last_counts``.
    """

    def __init__(self, predictor: PolarityPredictor, contour_map, K: np.ndarray, motion, calibration=None):
        self.predictor = predictor
        self.map = contour_map
        self.K = np.asarray(K, np.float64)
        self.motion = motion
        self.calibration = calibration
        self.last_counts: dict = {}
        self.fused_pose = True
        """Whether the pose that follows is the IMU fusion's (``full``); False in ``stpe+filter``, whose prediction is the
        constant-velocity filter's (``reopen_contradicted_unfused``)."""
        self.latest_state = None
        """The fusion's adapter (its ``last`` fused state) when the motion is taken without IMU propagation
        (``unfused_latest_motion``, ``stpe+filter``), else None."""
        self.hold_updates = 0
        """For the next this many updates every point takes both polarities and :meth:`align` composes no ``T_align``
        (registration reads the plain fields; :meth:`align` counts them down): set at a start without the initial
        velocity (``PolarityFilterConfig.unknown_velocity_hold_updates``)."""
        self._aligned = None
        self._aligned_fresh = False
        """True between :meth:`align` and the :meth:`observe` of the same step (the grid is this step's)."""
        self._dropped = 0
        """Points :meth:`points_to_register` dropped this step for an empty patch (they count in the covariance)."""
        self._dropped_slow = 0
        """Points :meth:`points_to_register` dropped this step as predicted not to fire (``register_min_normal_speed_px_s``)."""
        self._step_points: tuple[np.ndarray, np.ndarray] | None = None
        """(map indices, predicted polarity) of this step's :meth:`__call__`: every point :meth:`align` composed."""

    def align(self, surface, points_world: np.ndarray, T_world_cam: np.ndarray, polarity: np.ndarray,
              roi: tuple[int, int, int, int] | None, events=None, keep: np.ndarray | None = None, t_us: int | None = None):
        """The event filter: ``T_align`` of ``surface`` for the used points and their predicted ``polarity``, or None when
        ``config.event_filter`` is off (then registration reads per-point polarity fields of ``surface``).

        The returned surface feeds the distance field (slot 0 only); counts of
        the events it removed are merged into :attr:`last_counts`. :meth:`points_to_register`
        then says which of the points registration needs.
        """
        c = self.predictor.config
        if not (c.enabled and c.event_filter):
            return None
        if self.hold_updates > 0:
            self.hold_updates -= 1
            return None
        from evpose.fusion.aligned_surface import AlignedTimeSurface

        if self._aligned is None or (self._aligned.width, self._aligned.height) != (surface.width, surface.height):
            self._aligned = AlignedTimeSurface(surface.width, surface.height, self.calibration)
        out = self._aligned.compose(surface, points_world, T_world_cam, self.K, polarity, c.align_patch_radius_px, roi, events, keep,
                                    t_us, c.empty_after_eta, c.patch_radius_px,
                                    c.reopen_contradicted or c.drop_empty_points or (c.reopen_contradicted_unfused and not self.fused_pose),
                                    defer_events=not self.fused_pose)
        # ``stpe+filter``: the events are labelled in :meth:`observe`, off the registration's path. Not in ``full``, whose
        # latency counts the whole update: labelled after the fusion, the grid is colder and the pass costs more than it
        # saves (346x260 seeds 0-3, plain / textured landing: align -0.07 / -0.12 ms, labelling +0.09 / +0.17 ms).
        self._aligned_fresh = True
        self.last_counts.update(out.last_counts)
        return out

    def points_to_register(self) -> np.ndarray | None:
        """bool (M,) over the points of the last :meth:`align`: those registration needs (None: use all). Drops the
        points whose patch shows no recent accepted event (``drop_empty_points``) and those predicted to fire almost
        no events, their image motion nearly along their edge (``register_min_normal_speed_px_s``); only with a
        ``T_align`` built this step."""
        c = self.predictor.config
        self._dropped = self._dropped_slow = 0
        if not (self._aligned_fresh and self._aligned is not None):
            return None
        keep = None
        if c.drop_empty_points:
            keep = self._aligned.point_has_events.copy()
            self._dropped = int(keep.size - np.count_nonzero(keep))
        last = self.predictor.last
        if float(c.register_min_normal_speed_px_s) > 0 and last is not None and last.speed_px_s.size == self._aligned.last_point_count:
            speed = last.speed_px_s.astype(np.float64)
            angle = np.radians(last.angle_deg.astype(np.float64))
            # No defined angle = no motion (or no projected normal): the speed alone says it. NaN speed (behind the
            # camera) compares False: kept, registration handles it.
            normal = np.where(np.isfinite(angle), speed * np.abs(np.cos(angle)), speed)
            slow = normal < float(c.register_min_normal_speed_px_s)
            if keep is None:
                keep = np.ones(slow.size, np.bool_)
            slow &= keep
            self._dropped_slow = int(np.count_nonzero(slow))
            keep &= ~slow
        return keep

    def registration_covariance(self, registration, config) -> np.ndarray | None:
        """The covariance of ``registration`` (a :class:`~evpose.tracker.registration.RegistrationResult` over the
        points :meth:`points_to_register` kept) as if the dropped points had been registered too.

        A dropped point reads the field's "never fired" value (TDF 1, no gradient): it adds nothing to ``J^T W J``
        but, with ``residual_variance: all``, its ``w r^2`` to the residual variance. Without that share the
        covariance shrinks with every dropped point (about 2x in standard deviation at 60 % dropped) and the fusion
        or the motion filter trusts the registration more than before (measured: ``full`` 15.6 / 19.7 mm with it,
        16.8 / 22.6 mm without, simulated landing seed 0, 346x260 / 240x180).
        """
        from evpose.tracker.registration import _LOSS_ID, RobustLoss, ResidualVariance, _rho_weight  # the registration's own loss

        cov = registration.covariance
        if cov is None or not self._dropped or ResidualVariance(config.residual_variance) is not ResidualVariance.ALL:
            return cov
        w = np.asarray(registration.weights, np.float64)
        r = np.asarray(registration.residuals, np.float64)
        share = float(np.dot(w, r * r))
        if not share > 0:
            return cov
        _, w1 = _rho_weight(1.0, _LOSS_ID[RobustLoss(config.robust_loss)], float(config.robust_scale))
        return cov * ((share + self._dropped * w1) / share)

    def __call__(self, T_world_cam: np.ndarray, t_us: int, map_indices: np.ndarray) -> np.ndarray:
        self._aligned_fresh = False
        self._dropped = self._dropped_slow = 0
        idx = np.asarray(map_indices, np.int64)
        omega, velocity = self._motion(int(t_us))
        m = self.map
        # The map's arrays with the indices (read in place by the kernels): the same values as gathering them first.
        pol = self.predictor.predict_full(m.points, m.edge_normal, m.brightness_sign, T_world_cam, omega,
                                          velocity, self.K, idx, rows=idx).polarity
        if self.hold_updates > 0:
            pol = np.zeros_like(pol)  # the velocity is not known yet: every point takes both polarities
        single = int(np.count_nonzero(pol))
        self.last_counts = {"points": int(idx.size), "points_single_polarity": single, "points_both": int(pol.size) - single}
        self._step_points = (idx, pol)
        return pol

    def _motion(self, t_us: int) -> tuple[np.ndarray, np.ndarray]:
        """(bias-corrected angular rate in the camera frame, camera velocity in the world) at ``t_us``.

        From the fusion's IMU prediction to ``t_us``, or with :attr:`latest_state` (``stpe+filter``) from the gyro at
        ``t_us`` less the latest fused gyro bias and the latest fused velocity (one update old) moved on by one
        accelerometer step, so no IMU propagation runs before the pose: its fusion update integrates the same span after
        the pose is out."""
        last = None if self.latest_state is None else self.latest_state.last
        if last is None or not hasattr(self.motion, "buffer"):
            view = getattr(self.motion, "predict_view", None)  # read only below: no copy of the state
            state = view(t_us) if view is not None else self.motion.predict(t_us)
            return (np.zeros(3) if state.omega_cam is None else state.omega_cam), state.velocity_world
        acc, gyro = self.motion.buffer.measurement_at(t_us)
        velocity = last.velocity_world
        dt = (int(t_us) - int(last.t_us)) * 1e-6
        if dt > 0:
            # One accelerometer step from the latest fused state (world z up, gravity -z as the fusion's preintegration
            # has it; the lever arm's share left out): the velocity at ``t_us`` without the preintegration. Without it
            # (the state's velocity as it is) ``stpe+filter`` lost 0.03-0.11 mm (session 30, see the config field).
            R_world_imu = last.T_world_cam[:3, :3] @ self.motion.extrinsic.R_cam_imu
            acc_world = R_world_imu @ (acc - last.acc_bias)
            acc_world[2] -= float(self.motion.config.gravity)
            velocity = velocity + acc_world * dt
        return self.motion.extrinsic.cam_omega(gyro - last.gyro_bias), velocity

    def observe(self, events, T_world_cam: np.ndarray, map_indices: np.ndarray, polarity: np.ndarray,
                width: int, height: int, keep: np.ndarray | None = None) -> np.ndarray:
        """Label the step's events (1 kept, 0 removed by polarity, -1 in no patch), learn signs; returns the labels.

        ``keep`` (optional): ``events`` is the whole batch and only ``events[keep]`` are labelled (the labels are
        those of ``observe(events[keep], ...)``); when they are the events this step's ``T_align`` judged, its labels
        and per-point majorities are used and no copy of the kept events is made (a view is returned then).

        Events are on sensor pixels; with a distorted ``calibration`` they are
        moved to the ideal pinhole frame the map is projected in. When
        :meth:`points_to_register` dropped points, ``map_indices`` / ``polarity``
        may be the registered subset: labels and sign votes are still taken over
        every point of the step's prediction (the grid :meth:`align` built), so
        dropped points keep learning their signs and no second grid is built.
        """
        idx = np.asarray(map_indices, np.int64)
        step = self._step_points
        if ((self._dropped or self._dropped_slow) and step is not None and self._aligned_fresh and self._aligned is not None
                and step[0].size == self._aligned.last_point_count):
            idx, polarity = step
        r = self.predictor.config.patch_radius_px
        fresh = self._aligned_fresh and self._aligned is not None and self._aligned.last_point_count == idx.size
        if keep is not None:
            judged = self._aligned.batch_judgement(events, keep, r) if fresh else None
            if judged is not None:
                label, majority = judged
                self._aligned_fresh = False
                self.predictor.learn(idx, majority)
                self.last_counts.update(self._aligned.last_counts)  # now with T_align's event counts
                self.last_counts.update(filter_summary(label))
                return label
            events = events[keep]
        if fresh:
            # This step's T_align grid already knows each pixel's nearest point (at the predicted pose, within
            # ~1 px of the registered one): label from it instead of building another nearest-point grid.
            judged = self._aligned.kept_labels(events, r)  # usually labelled in compose's counting pass already
            label, point = judged if judged is not None else self._aligned.classify(events, r)
        else:
            T = np.asarray(T_world_cam, np.float64)
            X = (self.map.points[idx] - T[:3, 3]) @ T[:3, :3]
            with np.errstate(divide="ignore", invalid="ignore"):
                z = np.where(X[:, 2] > 1e-9, X[:, 2], np.nan)
                uv = np.stack([self.K[0, 0] * X[:, 0] / z + self.K[0, 2], self.K[1, 1] * X[:, 1] / z + self.K[1, 2]], axis=1)
            x, y = events.x.astype(np.float64), events.y.astype(np.float64)
            cal = self.calibration
            if cal is not None and getattr(cal, "dist", ()):
                table = cal.undistortion_table
                xy = table[events.y, events.x].astype(np.float64)
                x, y = xy[:, 0], xy[:, 1]
            label, point = classify_events(x, y, events.p, uv, polarity, r, width, height)
        self._aligned_fresh = False
        self.predictor.learn(idx, observed_point_polarity(point, events.p, idx.size))
        if fresh:
            self._aligned.judge()
            self.last_counts.update(self._aligned.last_counts)
        self.last_counts.update(filter_summary(label))
        return label

    def snapshot(self) -> dict:
        """Learned signs (the motion source is snapshotted by its owner)."""
        return {"predictor": self.predictor.snapshot(), "last_counts": dict(self.last_counts), "hold_updates": self.hold_updates}

    def restore(self, snap: dict) -> None:
        self.predictor.restore(snap["predictor"])
        self.last_counts = dict(snap["last_counts"])
        self.hold_updates = int(snap.get("hold_updates", 0))
        self._aligned_fresh = False
