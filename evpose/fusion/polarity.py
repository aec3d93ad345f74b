"""Polarity prediction for map points (EV-Pose MHFO early stage, section V-A).

The rule, stated once. The brightness gradient of a map point (dark -> bright)
is ``g = brightness_sign * edge_normal`` in the world (ContourMap convention).
Its image direction is ``J_pi(X_c) R_cw g``. The point's image motion is the
motion field ``u_dot = J_pi(X_c) (-omega x X_c - R_cw v)`` from the camera's
angular rate ``omega`` (camera frame, bias-corrected gyro), its world velocity
``v`` and the point's depth. Brightness constancy ``dL/dt = -grad L . u_dot``
makes the pixel brighter (ON, +1) when the image gradient and the image motion
are opposed (angle > 90 deg) and darker (OFF, -1) when they agree.

Buffer zone: within ``delta`` of 90 deg the prediction is unreliable and the
point keeps both polarities (0). ``delta`` widens adaptively by the angle the
flow uncertainty subtends, ``atan(flow_sigma / |u_dot|)``, so slow or
uncertain motion widens it; below ``min_image_speed`` everything is 0.

Online sign learning: each point's sign is learned from the polarities it
triggers, ``sign = observed * geometric`` where ``geometric`` is the
prediction with sign +1; votes accumulate per map point. Points without a map
sign use the learned one; with ``learned_overrides_map`` a confident learned
sign also replaces a contradicting map sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

# The per-event labelling moved to its own module; re-exported here, where it was (imports and docs name it here).
from evpose.fusion.event_labels import classify_events, filter_summary, observed_point_polarity  # noqa: F401
# The settings live in their own module; re-exported here, where they were.
from evpose.fusion.polarity_config import PolarityFilterConfig  # noqa: F401


@dataclass
class PolarityPrediction:
    """Per-point prediction with the quantities behind it (for the viewer and reports)."""

    polarity: np.ndarray
    """+1 / -1 / 0 (buffer zone: both), int8 (N,)."""
    angle_deg: np.ndarray
    """Angle between projected gradient and image motion, degrees (NaN if undefined), float32 (N,)."""
    speed_px_s: np.ndarray
    """Image speed of the point, px/s, float32 (N,)."""
    buffer_deg: np.ndarray
    """Buffer half-width used for the point, degrees, float32 (N,)."""
    geometric: np.ndarray
    """Prediction with brightness sign +1 (the learning reference), int8 (N,)."""


def image_motion(points_world, edge_normal_world, T_world_cam, omega_cam, v_world, K):
    """Projected edge-normal direction and motion field per point: (normal_img (N,2), flow_px_s (N,2), depth (N,))."""
    P = np.asarray(points_world, np.float64).reshape(-1, 3)
    n = np.asarray(edge_normal_world, np.float64).reshape(-1, 3)
    T = np.asarray(T_world_cam, np.float64)
    R_cw = T[:3, :3].T
    X = (P - T[:3, 3]) @ R_cw.T
    nc = n @ R_cw.T
    v_c = R_cw @ np.asarray(v_world, np.float64).reshape(3)
    Xdot = -np.cross(np.asarray(omega_cam, np.float64).reshape(3), X) - v_c
    fx, fy = K[0, 0], K[1, 1]
    Z = X[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        iz = np.where(Z > 1e-9, 1.0 / Z, np.nan)

        def jac(d):
            return np.stack([fx * (d[:, 0] - X[:, 0] * iz * d[:, 2]) * iz, fy * (d[:, 1] - X[:, 1] * iz * d[:, 2]) * iz], axis=1)

        return jac(nc), jac(Xdot), Z


_DEG = 180.0 / np.pi  # np.degrees' factor


@nb.njit(cache=True, error_model="numpy")  # 0/0 -> NaN as in numpy (no motion: undefined angle)
def _geometric_kernel(P, nw, rows, R_cw, t_wc, omega, v_c, fx, fy, f_mean, buf_deg, flow_sigma, max_buf, min_speed, min_vis,
                      angle, speed, buffer, geometric):
    """Per point: :func:`image_motion` and the sign-+1 prediction of :meth:`PolarityPredictor.predict_full` in one pass.

    The numpy version spends ~0.7 ms per tracker update on ~40 small-array operations for 1500 points;
    this loop does the same arithmetic (same formulas, NaN propagation and comparisons) in ~20 us.
    ``angle`` / ``speed`` / ``buffer`` may be float32: each float64 result is then rounded once, as ``astype`` would.
    Output ``i`` is point ``rows[i]`` of ``P`` / ``nw`` (the map's arrays are read in place, no gathered copies);
    float32 normals are widened exactly, so the arithmetic is that of their float64 copy.
    In a run it takes ~0.12 ms for ~930 points (57 us hot): not the reads of the map's rows, measured in session 14
    (points and normals packed into one 64-byte record per map point, caches flushed: 164 against 164-170 us).
    """
    for i in range(rows.shape[0]):
        j = rows[i]
        d0 = P[j, 0] - t_wc[0]
        d1 = P[j, 1] - t_wc[1]
        d2 = P[j, 2] - t_wc[2]
        X0 = d0 * R_cw[0, 0] + d1 * R_cw[0, 1] + d2 * R_cw[0, 2]
        X1 = d0 * R_cw[1, 0] + d1 * R_cw[1, 1] + d2 * R_cw[1, 2]
        Z = d0 * R_cw[2, 0] + d1 * R_cw[2, 1] + d2 * R_cw[2, 2]
        w0, w1, w2 = np.float64(nw[j, 0]), np.float64(nw[j, 1]), np.float64(nw[j, 2])
        n0 = w0 * R_cw[0, 0] + w1 * R_cw[0, 1] + w2 * R_cw[0, 2]
        n1 = w0 * R_cw[1, 0] + w1 * R_cw[1, 1] + w2 * R_cw[1, 2]
        n2 = w0 * R_cw[2, 0] + w1 * R_cw[2, 1] + w2 * R_cw[2, 2]
        # Xdot = -omega x X - v_c
        m0 = -(omega[1] * Z - omega[2] * X1) - v_c[0]
        m1 = -(omega[2] * X0 - omega[0] * Z) - v_c[1]
        m2 = -(omega[0] * X1 - omega[1] * X0) - v_c[2]
        iz = 1.0 / Z if Z > 1e-9 else np.nan
        gu = fx * (n0 - X0 * iz * n2) * iz
        gv = fy * (n1 - X1 * iz * n2) * iz
        fu = fx * (m0 - X0 * iz * m2) * iz
        fv = fy * (m1 - X1 * iz * m2) * iz
        sp = np.hypot(fu, fv)
        gn = np.hypot(gu, gv)
        vis = gn * Z / f_mean
        c = (gu * fu + gv * fv) / (gn * sp)
        if c < -1.0:
            c = -1.0
        elif c > 1.0:
            c = 1.0
        ang = np.arccos(c) * _DEG
        b = buf_deg + np.arctan2(flow_sigma, sp) * _DEG
        if b > max_buf:
            b = max_buf
        ok = np.isfinite(ang) and Z > 0 and sp >= min_speed and vis >= min_vis and abs(ang - 90.0) > b
        angle[i] = ang
        speed[i] = sp
        buffer[i] = b
        geometric[i] = (1 if ang > 90.0 else -1) if ok else 0


@nb.njit(cache=True)
def _sign_kernel(geometric, brightness_sign, rows, point_index, use_index, votes, min_votes, overrides, enabled, out):
    """Per point: the brightness sign (the map's, or the learned one of :meth:`PolarityPredictor.learned_sign` where
    the map has none or ``overrides``) times the sign-+1 prediction; all 0 when not ``enabled``.

    One pass instead of ~12 numpy operations (lookup, thresholds, ``where``, casts) per tracker update.
    """
    n_votes = votes.shape[0]
    for i in range(geometric.shape[0]):
        s = brightness_sign[rows[i]]  # the map's sign of output point i (``rows`` as in _geometric_kernel)
        if use_index:
            k = point_index[i]
            learned = 0
            if k < n_votes:
                if k < 0:
                    k += n_votes  # numpy's negative indexing, as the array lookup of learned_sign does
                v = votes[k]
                if abs(v) >= min_votes:
                    learned = 1 if v > 0 else (-1 if v < 0 else 0)
            if learned != 0 and (s == 0 or overrides):
                s = learned
        out[i] = geometric[i] * s if enabled else 0


@nb.njit(cache=True)
def _votes_needed(point_index, observed, geometric):
    """1 + the largest point index with a non-zero vote ``observed * geometric`` (0: no vote)."""
    need = 0
    for i in range(point_index.shape[0]):
        if np.int32(observed[i]) * np.int32(geometric[i]) != 0 and point_index[i] + 1 > need:
            need = point_index[i] + 1
    return need


@nb.njit(cache=True)
def _add_votes(point_index, observed, geometric, votes):
    """``votes[point_index] += observed * geometric`` in order (repeated indices accumulate, as ``np.add.at``)."""
    for i in range(point_index.shape[0]):
        vote = np.int32(observed[i]) * np.int32(geometric[i])
        if vote != 0:
            votes[point_index[i]] += vote


class PolarityPredictor:
    """Predicts ON/OFF per visible map point and learns unknown brightness signs online."""

    def __init__(self, config: PolarityFilterConfig | None = None):
        self.config = config or PolarityFilterConfig()
        self._votes = np.zeros(0, np.int32)
        self._last_index: np.ndarray | None = None
        self._last_geometric: np.ndarray | None = None
        self.last: PolarityPrediction | None = None

    # ------------------------------------------------------------ prediction
    def predict_full(self, points_world, edge_normal_world, brightness_sign, T_world_cam, omega_cam, v_world, K,
                     point_index: np.ndarray | None = None, rows: np.ndarray | None = None) -> PolarityPrediction:
        """As :meth:`predict`, with the per-point geometry. ``rows`` (optional) predicts only those rows of the three
        per-point arrays (e.g. the whole map's arrays and the visible indices: no gathered copies per step)."""
        c = self.config
        P = np.ascontiguousarray(points_world, np.float64).reshape(-1, 3)
        if rows is None:
            rows = np.arange(P.shape[0], dtype=np.int64)
            normals = np.ascontiguousarray(edge_normal_world, np.float64).reshape(-1, 3)
            signs = np.ascontiguousarray(brightness_sign, np.int8).reshape(P.shape[0])
        else:
            rows = np.ascontiguousarray(rows, np.int64).reshape(-1)
            normals = np.asarray(edge_normal_world)
            if normals.dtype not in (np.float32, np.float64) or not normals.flags.c_contiguous:
                normals = np.ascontiguousarray(normals, np.float64)
            normals = normals.reshape(-1, 3)
            n_all = P.shape[0]
            if normals.shape[0] != n_all or np.size(brightness_sign) != n_all:
                raise ValueError("points, normals and brightness signs differ in length")
            if rows.size and (int(rows.min()) < -n_all or int(rows.max()) >= n_all):
                raise IndexError(f"point rows out of range for {n_all} points")  # the kernels do not check bounds
            signs = np.ascontiguousarray(brightness_sign, np.int8).reshape(n_all)
        N = rows.shape[0]
        T = np.asarray(T_world_cam, np.float64)
        R_cw = np.ascontiguousarray(T[:3, :3].T)
        angle = np.empty(N, np.float32)
        speed = np.empty(N, np.float32)
        buffer = np.empty(N, np.float32)
        geometric = np.empty(N, np.int8)
        _geometric_kernel(P, normals, rows, R_cw, np.ascontiguousarray(T[:3, 3]),
                          np.asarray(omega_cam, np.float64).reshape(3), R_cw @ np.asarray(v_world, np.float64).reshape(3),
                          float(K[0, 0]), float(K[1, 1]), float(0.5 * (K[0, 0] + K[1, 1])), float(c.buffer_deg), float(c.flow_sigma_px_s),
                          float(c.max_buffer_deg), float(c.min_image_speed_px_s), float(c.min_gradient_visibility), angle, speed, buffer, geometric)
        # The kernel: image direction of the normal and motion field (:func:`image_motion`), speed, angle,
        # adaptive buffer; foreshortening = image length of the unit normal relative to one parallel to the
        # image plane; brightness constancy: opposed gradient and motion (angle > 90 deg) -> ON for a +1 sign.
        # Then the sign: the map's, or the learned one (see learned_sign) where the map has none or it overrides.
        if point_index is not None:
            point_index = np.ascontiguousarray(point_index, np.int64).reshape(N)
        pol = np.empty(N, np.int8)
        _sign_kernel(geometric, signs, rows,
                     point_index if point_index is not None else np.zeros(0, np.int64), point_index is not None, self._votes,
                     int(c.learn_min_votes), bool(c.learned_overrides_map), bool(c.enabled), pol)
        self._last_index = point_index
        self._last_geometric = geometric
        self.last = PolarityPrediction(pol, angle, speed, buffer, geometric)
        return self.last

    def predict(self, points_world, edge_normal_world, brightness_sign, T_world_cam, omega_cam, v_world, K,
                point_index: np.ndarray | None = None) -> np.ndarray:
        """int8 (N,) in {+1, -1, 0 (buffer zone or unknown sign: use both)}.

        ``point_index`` (map indices of the points) enables learned signs for
        points whose ``brightness_sign`` is 0 and lets :meth:`learn` use this call.
        """
        return self.predict_full(points_world, edge_normal_world, brightness_sign, T_world_cam, omega_cam, v_world, K, point_index).polarity

    # -------------------------------------------------------------- learning
    def learned_sign(self, point_index: np.ndarray) -> np.ndarray:
        """Learned brightness sign per map point (0 until ``learn_min_votes`` net votes)."""
        idx = np.asarray(point_index, np.int64)
        out = np.zeros(idx.shape, np.int8)
        ok = idx < self._votes.shape[0]
        v = self._votes[idx[ok]]
        out[ok] = np.where(np.abs(v) >= self.config.learn_min_votes, np.sign(v), 0)
        return out

    def learn(self, point_index, observed_polarity) -> None:
        """Vote each point's brightness sign from the polarity it triggered (0 = no evidence).

        Uses the geometry of the last :meth:`predict` call that was given ``point_index``.
        """
        if self._last_index is None:
            return
        idx = np.asarray(point_index, np.int64).ravel()
        obs = np.asarray(observed_polarity, np.int8).ravel()
        if idx.shape == self._last_index.shape and np.array_equal(idx, self._last_index):
            geo = self._last_geometric  # the tracker learns on the points it just predicted: no lookup needed
        else:
            order = np.argsort(self._last_index, kind="stable")
            pos = np.searchsorted(self._last_index[order], idx)
            pos = np.clip(pos, 0, max(order.size - 1, 0))
            found = (order.size > 0) & (self._last_index[order[pos]] == idx) if order.size else np.zeros(idx.shape, bool)
            geo = np.where(found, self._last_geometric[order[pos]] if order.size else 0, 0)
        geo = np.ascontiguousarray(geo, np.int8)
        need = int(_votes_needed(idx, obs, geo))
        if need == 0:
            return
        if need > self._votes.shape[0]:
            self._votes = np.concatenate([self._votes, np.zeros(need - self._votes.shape[0], np.int32)])
        _add_votes(idx, obs, geo, self._votes)

    def snapshot(self) -> dict:
        return {"votes": np.copy(self._votes),
                "last_index": None if self._last_index is None else np.copy(self._last_index),
                "last_geometric": None if self._last_geometric is None else np.copy(self._last_geometric)}

    def restore(self, snap: dict) -> None:
        self._votes = np.copy(snap["votes"])
        self._last_index = None if snap["last_index"] is None else np.copy(snap["last_index"])
        self._last_geometric = None if snap["last_geometric"] is None else np.copy(snap["last_geometric"])


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
        ``t_us`` less the latest fused gyro bias and the latest fused velocity (one update old), so no IMU propagation
        runs before the pose: its fusion update integrates the same span after the pose is out."""
        last = None if self.latest_state is None else self.latest_state.last
        if last is None or not hasattr(self.motion, "buffer"):
            state = self.motion.predict(t_us)
            return (np.zeros(3) if state.omega_cam is None else state.omega_cam), state.velocity_world
        _, gyro = self.motion.buffer.measurement_at(t_us)
        return self.motion.extrinsic.cam_omega(gyro - last.gyro_bias), last.velocity_world

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
