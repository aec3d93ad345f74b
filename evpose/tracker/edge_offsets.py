"""Online per-point edge offsets with the pose's gauge projected out: each registered map point slides along its
edge normal towards its field's minimum, but only by the part of the offsets no pose change explains.

Where the TDF minimum of an edge sits relative to the mapped edge varies from edge to edge and along an edge
(the map's own error; for the field: contrast, the pixels' thresholds, neighbouring structure), slowly over time:
on the simulated landing (240x180, seed 0, built map with its points moved onto the true edges, ``stpe`` closed
loop, field sampled at the truth) the Newton step to the minimum along each point's normal, averaged per edge and
update, spreads by 0.16 px (0.17 px within such a group), 44 % of it a static per-edge part. Registration takes
such offsets as pose error along the weakly observed tilt-vs-sideways direction. A per-point oracle (each of those
points moved by its mean offset over that run, refinement off) took ``stpe`` from 16.71 to 13.84 mm there; one
mean per edge, 18.57 mm.

Learning offsets at the *estimated* pose (as :mod:`evpose.tracker.map_refinement` does for painted edges) also
learns the pose's error: the map follows the pose and locks its error in. Here each update's offsets are first
fitted by a 6-DoF pose change (least squares on the points' pose Jacobians projected on their normals) and only
what that fit leaves is accumulated: a map change the pose could absorb is never learned. As the view changes the
projection changes, so a bias that at one moment looks like a pose change is learned at another. The fit is also
handed to the painted-edge refiner, which takes it out of its own steps.

Where the gain comes from (``stpe``, 240x180, seeds 0-3, defaults): built map 16.80 -> 13.80 mm (with this
config's ``field_lag_ms``); the built map's points moved onto the true edges 17.83 -> 15.59 mm with the painted
refiner, 15.54 -> 15.71 mm without it. So it mostly corrects the map (the geometric edges the painted refiner
leaves alone) and the painted refiner's locked-in pose error, not the field's own per-edge bias.

Offsets are metres along each point's map edge normal, written into the registration's copy of the map. 0.06 ms
(median, p99 0.14 ms) per update at 240x180: one pass over the registered points whose edge fired.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.frontend.distance_field import bilinear_curvature_from_value, bilinear_sample
from evpose.tracker.anchored_rims import AnchoredRimConfig
from evpose.tracker.camera_point import camera_point, fill_image_rows
from evpose.tracker.offset_fit import add_offset_row, apply_offset_fit, normal_px_per_m
from evpose.tracker.registration_kernels import _NO_EXTRA, _NO_TWIST, _floor_shift, _projected_normal


@dataclass
class EdgeOffsetConfig:
    """Gauge-free online offsets of the registered points (all modes, coarse sensors)."""

    enabled: bool = True
    """Learn per-point offsets along the edge normals with the pose's gauge projected out (see the module).

    ``stpe``, 2 s landing from ground truth, built map, 240x180 (the only resolution it runs at by default, see
    ``min_pixel_mrad``), mean ATE / ARE of seeds 0-3 and 4-7: off 16.80 / 0.250 and 17.95 mm / 0.236 deg; on (with
    its ``field_lag_ms``) 13.80 / 0.224 and 14.60 mm / 0.220 deg, no update lost."""
    stpe_filter: bool = True
    """Also in ``stpe+filter``, from the field registration reads there (``T_align``: the used points' patches).

    2 s landing from ground truth, built map, mean ATE seeds 0-3 / 4-7. 240x180 (on, with
    ``stpe_filter_field_lag_ms`` 5.5): 18.71 / 17.37 -> 15.85 / 14.20 mm. 346x260 (off: ``min_pixel_mrad``): with
    registration's 4.5 ms lag 14.78 / 12.56 -> 13.58 / 12.55 mm, with 5.0 ms 13.84 / 12.45 mm: too little on 4-7."""
    stpe_filter_field_lag_ms: float = field(default=6.0, metadata={"min": 0.0, "max": 50.0, "step": 0.1, "unit": "ms"})
    """``registration.field_lag_ms`` in ``stpe+filter`` while the offsets are learned (0 = keep that), milliseconds.

    240x180 seeds 0-3: 4.5 / 5.0 / 5.5 / 6.0 ms gave 16.62 / 16.34 / 15.85 / 16.19 mm (seeds 4-7: 5.0 14.86, 5.5
    14.20 mm); 5.5 without the learner 18.83 mm. ``gain`` 0.3 / 0.7 at 5.5: 16.37 / 16.01, ``step_clip_px`` 0.8:
    16.45 mm. Session 14, with ``map_refinement.hold_out_filtered`` (seeds 0-7): 5.5 / 6.0 ms 14.50 / 14.17 mm, with
    ``polarity.reopen_contradicted_unfused`` too 14.75 / 14.12 mm: 6.0, the lag ``stpe`` learns with (``field_lag_ms``)."""
    full: bool = True
    """Also in ``full``, from ``T_align``'s field and where registration samples it (its lag floor and polarity
    trail, :func:`evpose.tracker.registration_kernels._floor_shift`; sampled at the projection instead: 240x180
    seeds 0-3 8.50 mm at 5.0 ms).

    Mean ATE seeds 0-3 / 4-7 (fused output). 240x180 (on, ``full_field_lag_ms`` 5.0): 9.40 / 11.38 -> 8.11 /
    10.46 mm. 346x260 (off: ``min_pixel_mrad``): at registration's 4.5 ms 7.77 -> 7.90 mm (``gain`` 0.25 7.76,
    without ``gauge_painted`` 7.86), at 4.0 ms 7.42 / 8.30 mm (base 7.77 / 7.95), at 3.5 ms 7.64 / 8.48 mm, at
    5.0 ms 8.83 mm (seeds 0-3); registration's lag alone at 4.0 ms 7.82 mm. Session 12, with the events registered
    (:mod:`evpose.tracker.event_registration`; 6.38 / 7.25 mm at 346x260 / 240x180, seeds 0-3): on at 346x260 too,
    ``full_field_lag_ms`` 5.0 / 4.0, 6.96 / 6.48 mm; off at 240x180 7.55 mm. Session 38 (240x180 2 s seeds 0-23, CLI
    path paired against main's defaults 4.982 mm, ``/tmp/s38/tr38`` ``run.sh``, ``cmp.py``): off 5.242 mm (+0.26 +- 0.12,
    8 of 24 better), but ``gain`` 0 (the learner kept, its ``full_field_lag_ms`` too, no point moved) 5.040 (+0.058 +-
    0.068, 13 of 24): what pays now is the lag this brings, not the learned offsets (the events' own: neither, see
    ``EventRegistrationConfig.offset_gain``)."""
    full_field_lag_ms: float = field(default=5.0, metadata={"min": 0.0, "max": 50.0, "step": 0.1, "unit": "ms"})
    """``registration.field_lag_ms`` in ``full`` while the offsets are learned (0 = keep that), milliseconds.

    240x180 seeds 0-3: 4.5 / 4.75 / 5.0 / 5.25 / 5.5 / 6.0 ms gave 8.39 / 8.15 / 8.11 / 8.47 / 9.12 / 10.30 mm (seeds
    4-7: 4.75 11.00, 5.0 10.46 mm); 5.0 without the learner 9.23 mm. At 5.0 ``gain`` 0.25 / 0.3 / 0.7 gave 8.74 /
    8.39 / 8.15 mm (0.7 on 4-7: 10.62), ``step_clip_px`` 0.8 8.23 mm."""
    min_pixel_mrad: float = field(default=5.0, metadata={"min": 0.0, "max": 100.0, "step": 0.1, "unit": "mrad"})
    """Only when one pixel subtends at least this angle (``1 / fx``), milliradians (0 = any sensor).

    The simulated landing's 70 deg cameras: 4.05 mrad at 346x260 (off), 5.83 mrad at 240x180 (on). At 346x260 (0,
    ``gain`` 0.5, ``step_clip_px`` 1.2, ``field_lag_ms`` as registration's 4.5 ms) seeds 0-3 / 4-7 went 12.40 / 11.66
    -> 12.53 / 11.20 mm: mixed, so off there."""
    gain: float = field(default=0.5, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Share of each update's gauge-free offset a point moves by, ratio.

    Seeds 0-3 / 4-7 at 240x180 (``step_clip_px`` 1.2, ``field_lag_ms`` 5.5): 0.3 / 0.5 / 0.7 gave 14.46 / 14.88,
    14.04 / 14.57, 14.23 / 14.99 mm; with ``step_clip_px`` 0.3 (seeds 0-3) 0.01 / 0.03 / 0.1 / 0.2 / 0.4 / 0.7 /
    1.0 gave 16.20 / 16.31 / 15.92 / 15.79 / 15.53 / 15.32 / 15.74 mm."""
    step_clip_px: float = field(default=1.2, metadata={"min": 0.01, "max": 5.0, "step": 0.05, "unit": "px"})
    """A point whose offset in one update is larger than this takes no part in that update (its minimum is most
    likely another edge's), pixels.

    Seeds 0-3 at 240x180 (``gain`` 0.4, ``field_lag_ms`` 5.5): 0.5 / 0.8 / 1.2 / 2.0 gave 15.21 / 14.41 / 14.09 /
    14.37 mm (seeds 4-7: 15.32 / 15.30 / 15.15 / - mm); ``gain`` 0.5 with 1.5: 14.23 / 14.58 mm."""
    field_lag_ms: float = field(default=6.0, metadata={"min": 0.0, "max": 50.0, "step": 0.1, "unit": "ms"})
    """``registration.field_lag_ms`` while the offsets are learned (0 = keep that), milliseconds.

    The learned offsets keep what no pose explains; a trail the lag model leaves (at the truth on the true-edge map,
    240x180: the Newton step to the field's minimum is ``-0.09 px - 0.76 ms x normal speed`` beyond the 4.5 ms
    lag) largely looks like a pose change (the image's expansion while descending) and must be met by the lag.
    Seeds 0-3 / 4-7 at 240x180 (``gain`` 0.5, ``step_clip_px`` 1.2): 4.5 / 5.0 / 5.5 / 6.0 / 6.5 ms gave 15.03 /
    16.37, 14.58 / 15.54, 14.04 / 14.57, 13.80 / 14.60, 14.12 / 14.15 mm. Without the learner 5.0 / 5.5 / 6.0 / 6.5
    gave 16.48 / -, 16.40 / 16.79, 16.57 / -, 16.51 / - mm (4.5: 16.80 / 17.95)."""
    gauge_painted: bool = True
    """Take the pose-like part fitted on the other points out of the painted-edge refiner's steps too
    (:mod:`evpose.tracker.map_refinement`; it keeps the painted points, whose map error needs its fast start).
    Its steps bring the field to zero (Gauss-Newton, mostly clipped), not to the minimum, so this takes out only
    roughly the pose-like part. Seeds 0-3 / 4-7 at 240x180 without it: 14.65 / 15.09 mm (13.80 / 14.60 with it)."""
    max_offset_m: float = field(default=0.05, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest distance a point may move from the map's position, metres."""
    inlier_threshold: float = field(default=0.7, metadata={"min": 0.05, "max": 1.0, "step": 0.01, "unit": "TDF"})
    """Only points whose field value is below this take part (their edge fired), TDF units."""
    min_curvature: float = field(default=1e-3, metadata={"min": 0.0, "max": 1.0, "step": 1e-4, "unit": "TDF/px^2"})
    """Only points where the Newton curvature along the normal (``g^2 + f h``) is at least this take part, TDF/px^2."""
    min_px_per_m: float = field(default=5.0, metadata={"min": 0.0, "max": 1000.0, "step": 1.0, "unit": "px/m"})
    """Points whose map edge normal projects to less than this along the image normal are left alone, px/m."""
    anchored_rims: AnchoredRimConfig = field(default_factory=AnchoredRimConfig)
    """The rims' absolute refinement while other edges anchor the pose (:mod:`evpose.tracker.anchored_rims`; off)."""


@nb.njit(cache=True)
def _offset_kernel(points, idx, base, normals, tangents, offsets, R_cw, t_cw, fx, fy, cx, cy, value, grad_u, grad_v, box,
                   gain, clip_px, max_offset, thr, min_a, min_pxm, twist, lag_s, floor_px, extra, obs, pxm, jac, ok, fit_out):
    """One update: the Newton offsets (pixels) of the points ``idx`` along their image normals, their weighted 6-DoF
    fit (written to ``fit_out``, NaN if there are too few points) taken out, ``gain`` of the rest added to
    ``offsets`` (metres along ``normals``) and written into ``points``; returns how many moved. ``floor_px`` > 0 or
    a non-empty ``extra`` (M,) samples each point's field where registration does (the lag floor's and the per-point
    trail's shift, :func:`evpose.tracker.registration_kernels._floor_shift`, with ``twist`` (6,) and ``lag_s``).
    ``obs``, ``pxm`` (M,), ``jac`` (M, 6) and ``ok`` (M,) are scratch."""
    m = idx.shape[0]
    H = np.zeros((6, 6))
    b = np.zeros(6)
    n_ok = 0
    shifted = floor_px > 0.0 or extra.shape[0] > 0
    Ju = np.zeros(6)
    Jv = np.zeros(6)
    for r in range(6):
        fit_out[r] = np.nan
    for j in range(m):
        ok[j] = False
        i = idx[j]
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if Z <= 1e-6:
            continue
        iz = 1.0 / Z
        u = fx * X * iz + cx
        v = fy * Y * iz + cy
        nu, nv = _projected_normal(tangents, j, R_cw, X, Y, Z, fx, fy)
        if nu == 0.0 and nv == 0.0:
            continue
        # d u / dX, d u / dZ, d v / dY, d v / dZ: the image rows below (and the shift's image velocity).
        pux = fx * iz
        puz = -fx * X * iz * iz
        pvy = fy * iz
        pvz = -fy * Y * iz * iz
        us = u
        vs = v
        if shifted:
            # Registration reads this point's field behind its projection (the fused modes' lag floor and
            # polarity trail): the offset to learn is the one from there.
            fill_image_rows(X, Y, Z, pux, puz, pvy, pvz, Ju, Jv)
            du, dv = _floor_shift(tangents, j, R_cw, X, Y, Z, fx, fy, Ju, Jv, twist, lag_s, floor_px,
                                  extra[j] if extra.shape[0] else 0.0)
            us += du
            vs += dv
        f, fu, fv, inside = bilinear_sample(value, grad_u, grad_v, box, np.int64(0), us, vs)
        if not inside or f >= thr:
            continue
        huu, huv, hvv = bilinear_curvature_from_value(value, box, np.int64(0), us, vs)
        gn = fu * nu + fv * nv
        a = gn * gn + f * (nu * nu * huu + 2.0 * nu * nv * huv + nv * nv * hvv)
        if a < min_a:
            continue
        o = -f * gn / a  # the Newton step on 0.5 f^2 along the normal, as registration takes it
        if abs(o) > clip_px:
            continue
        p = normal_px_per_m(normals, j, R_cw, X, Y, Z, iz, nu, nv, fx, fy)
        if abs(p) < min_pxm:
            continue
        add_offset_row(H, b, jac, j, o, nu, nv, X, Y, Z, pux, puz, pvy, pvz)
        obs[j] = o
        pxm[j] = p
        ok[j] = True
        n_ok += 1
    return apply_offset_fit(H, b, n_ok, ok, idx, obs, pxm, jac, offsets, points, base, normals, True, gain, max_offset, fit_out)


class EdgeOffsetLearner:
    """Per map point offset along its edge normal (metres), learned online with the pose's gauge projected out."""

    def __init__(self, config: EdgeOffsetConfig, points: np.ndarray, edge_normal: np.ndarray, tangents: np.ndarray,
                 skip: np.ndarray | None = None):
        """``points`` (N, 3) the map's positions (copied: the base the offsets apply to), ``edge_normal`` (N, 3) its
        edge normals, ``tangents`` (N, 3) its unit edge directions (zero = unknown: such points are left alone);
        ``skip`` (N,) bool points left alone too (another refiner's)."""
        self.config = config
        self._base = np.array(points, dtype=np.float64, order="C")  # a copy: the caller's array is the one moved
        n = np.asarray(edge_normal, dtype=np.float64)
        self._normals = np.ascontiguousarray(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12))
        self._tangents = np.ascontiguousarray(tangents, dtype=np.float64)
        self._owned = np.any(n != 0, axis=1) & np.any(self._tangents != 0, axis=1)
        if skip is not None:
            self._owned &= ~np.asarray(skip, dtype=np.bool_)
        self.offsets = np.zeros(self._base.shape[0])
        """Current offset of each map point along its unit edge normal, metres."""
        self.last_fit = np.full(6, np.nan)
        """The last update's pose-like part of the offsets (right-perturbation tangent, rotation then translation),
        NaN when there was none (too few points): what the painted-edge refiner should not learn either."""

    @property
    def owned(self) -> int:
        """How many map points this learner may move (a known edge normal and direction, not another refiner's)."""
        return int(np.count_nonzero(self._owned))

    def update(self, points: np.ndarray, used: np.ndarray, field_, T_world_cam_field: np.ndarray, K: np.ndarray,
               twist: np.ndarray | None = None, lag_s: float = 0.0, floor_px: float = 0.0,
               trail_px: np.ndarray | None = None) -> int:
        """Learn from one update's field (combined slot) at the pose it shows (lag included) over the registered map
        points ``used`` (indices into ``points``), moving them in ``points``; returns how many moved.

        Registration's sampling shift (its lag floor ``floor_px`` and the points' ``trail_px`` (as ``used``), with
        ``twist`` the body twist per second and ``lag_s`` the lag the field pose carries) is applied when ``twist``
        is given and one of them is set: the offsets are then measured from where registration reads the field."""
        c = self.config
        keep = self._owned[used]
        idx = np.ascontiguousarray(used[keep], dtype=np.int64)
        if idx.size == 0:
            self.last_fit[:] = np.nan
            return 0
        xi, extra, floor = _NO_TWIST, _NO_EXTRA, 0.0
        if twist is not None and (floor_px > 0 or trail_px is not None):
            xi = np.ascontiguousarray(twist, dtype=np.float64).reshape(6)
            if np.all(np.isfinite(xi)):
                floor = float(floor_px)
                if trail_px is not None:
                    extra = np.ascontiguousarray(np.asarray(trail_px, dtype=np.float64)[keep])
            else:
                xi = _NO_TWIST
        T_cw = np.linalg.inv(np.asarray(T_world_cam_field, dtype=np.float64))
        m = idx.size
        return int(_offset_kernel(points, idx, self._base, np.ascontiguousarray(self._normals[idx]),
                                  np.ascontiguousarray(self._tangents[idx]), self.offsets, np.ascontiguousarray(T_cw[:3, :3]),
                                  np.ascontiguousarray(T_cw[:3, 3]), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
                                  field_.value, field_.grad_u, field_.grad_v, field_.box, float(c.gain), float(c.step_clip_px),
                                  float(c.max_offset_m), float(c.inlier_threshold), float(c.min_curvature), float(c.min_px_per_m),
                                  xi, float(lag_s), floor, extra, np.empty(m), np.empty(m), np.empty((m, 6)), np.empty(m, np.bool_), self.last_fit))

    def apply(self, points: np.ndarray) -> None:
        """Write the current offsets into ``points`` (after a restore), for the points this learner owns."""
        k = self._owned
        points[k] = self._base[k] + self.offsets[k, None] * self._normals[k]

    def snapshot(self) -> np.ndarray:
        return np.copy(self.offsets)

    def restore(self, state: np.ndarray) -> None:
        self.offsets = np.copy(state)
        self.last_fit[:] = np.nan
