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
# The tracker's adapter too (imports name it here).
from evpose.fusion.map_polarity_selector import MapPolaritySelector  # noqa: F401


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
    Tried in session 30, not kept: the buffer-zone test in cosine space (``|cos| > sin(b)``, ``sin(b)`` from the
    speed and ``flow_sigma`` with one square root, ``arccos`` / ``arctan2`` only within 1e-9 of the boundary; the
    angle and buffer outputs then computed on demand): the same decisions on all 393 updates of ``stpe+filter``'s
    seed-0 run, 85 -> 62 us per call replayed (``/tmp/s30/lat30/geo_fast.py``, ``geo_bench.py``), ~1.5 % of the
    filter's front end, not worth lazily computed outputs.
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
