"""Online refinement of a map's painted (brightness) edges while tracking: each point slides along its edge normal
towards where the events put the edge.

The map builder places geometric edges (crate rims, the pad's border) within a
millimetre, but painted edges (the landing 'H') only as well as the scan's
intensity steps allow: 10-12 mm median error, whole edges 5-27 mm off on the
simulated landing. Registration takes them as they are, and because the
tilt-vs-shift direction of a downward camera over flat ground is barely observed
(the cost changes by ~1 % over +-40 mm along it), their bias becomes a pose bias.

After each tracked update the refiner samples the update's distance field at the
painted points (projected with the pose moved back by the field's lag, as the
registration does), takes for each inlier point the Gauss-Newton step along its
projected edge normal that would bring its residual to zero, ``-f g_n / (g_n^2 +
eps)`` pixels (clipped), turns it into metres along the map normal and moves the
point by ``gain`` times it. The offsets of many updates average over the pose's
own errors, which change from update to update, while the map's error does not.
Geometric edges are left alone: they anchor the pose.

Only the points registration reads move; culling keeps the map's positions (its
block-wise superset is built once from them, and a few centimetres do not change
what is in view).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.frontend.distance_field import _bilinear_weights
from evpose.tracker.camera_point import camera_point, fill_image_rows
from evpose.core.lapack_calls import inv
from evpose.tracker.registration_kernels import _NO_EXTRA, _NO_TANGENTS, _NO_TWIST, _floor_shift


@dataclass
class MapRefinementConfig:
    """Online refinement of painted edges (all modes; the fused ones unless ``fused_modes`` is off)."""

    enabled: bool = True
    """Move painted-edge points along their edge normal to where the events put them, while tracking.

    Simulated landing, 2 s, ``stpe`` from ground truth on the built map, mean of seeds 0-3 (with
    ``first_updates`` 10): ATE 30.0 -> 24.5 mm, ARE 0.453 -> 0.353 deg at 346x260, 34.9 -> 31.1 mm,
    0.539 -> 0.475 deg at 240x180 (seed 0: 33.0 -> 18.7 and 42.2 -> 29.9 mm); the painted points'
    median error falls 11.9 -> 4.4 mm (seed 0) and 10.2 -> 7.3 mm (seed 2) over the 2 s (fixed gain).
    About 40 us per update. ``stpe+filter`` 30.5 -> 24.5 mm and 35.8 -> 32.5 mm; textured landing
    (seed 0, 346x260) ``stpe`` 62.4 -> 54.3 mm, ``stpe+filter`` 36.6 -> 26.1 mm. Bundled demos: landing
    ATE of the written poses 125 -> 126 mm (max 240 -> 253 mm), indoor 97 -> 90 mm. The fused modes refine
    too unless ``fused_modes`` is off.

    Session 7 split of the map's share (``stpe``, seeds 0-3, 346x260 / 240x180, before ``register_after_updates``
    and the filter's anisotropy, crowding radius 2.08 px at 240x180): built map 15.82 / 22.21 mm; every point
    moved onto its nearest true edge 14.32 / 19.97 mm, and without refinement 12.02 / 15.91 mm; the simulator's
    true edges (3 px crowding) 11.90 / 16.83 mm. The refiner's fixed point is the field's minimum, not the edge:
    on an accurate map it costs 2-4 mm, on the built one the painted edges (10 mm median error) need it. With
    the defaults, ``gain`` 0.03 / 0.05 / 0.1 gave 13.19 / 19.20, 13.42 / 19.00, 14.15 / 18.98 mm and
    ``step_clip_px`` 0.5 / 1.0 14.07 / 19.49, 16.90 / 21.74 mm; smoothing each painted point's position with
    its neighbours' (same normal, 3-25 cm) 13.50 / 18.01 mm at best (6 cm): not kept."""
    fused_modes: bool = True
    """Refine in the fused modes (``full``, where IMU fusion drives the pose) too.

    2 s landing from ground truth, mean of seeds 0-3 (``/tmp/s5/fused_refine.py``, session 5): ATE 13.45 -> 12.58 mm,
    ARE 0.171 -> 0.133 deg (346x260), 15.51 -> 15.25 mm, 0.198 -> 0.179 deg (240x180); seed 0 16.6 -> 15.0 and
    20.7 -> 18.4 mm, ARE 0.241 -> 0.150 and 0.312 -> 0.233 deg. Bundled demos (ATE RMSE, ``--align none``):
    ``landing`` 17.38 -> 16.81 mm, ``landing_dynamic`` 34.90 -> 28.85 mm, ``landing_fast`` 22.29 -> 22.66 mm
    (ARE 0.185 -> 0.212 deg): the one case it costs.

    Session 15, 346x260 (no edge-offset gauge there): the built map's painted 'H' is turned (a rigid fit of the
    offsets refined by 1.3 s: -0.6 / -0.1 deg about the vertical, seeds 0 / 2). Registered from the truth (no prior,
    seeds 0 / 2), the roll ends at -0.21 / -0.17 deg in the last 0.2 s without the refiner, -0.05 / -0.08 deg with it
    (true-edge map, refiner on: -0.07 / -0.02): the refiner corrects the map rather than following the pose. The edge
    offsets' pose fit handed to it as a gauge (``edge_offsets`` on at 346x260 with ``gain`` 0, the registration's lag
    kept): ``full`` seeds 0-3 6.40 mm against 6.38. Session 38 (``full``, 240x180 2 s seeds 0-23, CLI path paired against
    main's defaults 4.982 mm, ``/tmp/s38/tr38`` ``run.sh``, ``cmp.py``): off 6.152 mm (+1.17 +- 0.19, 3 of 24 better), the
    learned map state that matters most at 240x180 (the events' own offsets: none, see ``offset_gain``)."""
    gain: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Share of each update's measured step a point moves by (an average over ~1 / gain updates), ratio.

    Mean of seeds 0-3 at 346x260 / 240x180: 0.03 / 0.05 / 0.1 gave 26.5 / 26.2 / 26.8 mm and
    32.3 / 33.4 / 34.3 mm (most steps are clipped by ``step_clip_px``: 0.5 with 0.05 equals 0.1)."""
    fused_gain: float = field(default=0.03, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """``gain`` in the fused modes (``full``, where the fused pose the refiner reads carries the registrations' slow
    tilt-vs-sideways bias, which a slower average follows less; 0 = ``gain``), ratio.

    Session 38 (``full``, landing from ground truth, CLI path paired per seed against ``gain`` 0.05, main fd512ff;
    ``/tmp/s38/tr38`` ``run.sh``, ``cmp.py``, ``demo.sh``; mean ATE RMSE mm +- standard error, seeds better): 240x180
    2 s seeds 0-23 4.982 -> 0.03: **4.934** (-0.048 +- 0.033, 16 of 24), 0.1: 5.148 (+0.167 +- 0.037, 2 of 24), 0.02
    (after the choice; 24-47 5.309) 4.924: against 0.03 on 0-47 -0.027 +- 0.023 (29 of 48), not kept without other seeds;
    with 0.03, held-out seeds 24-47 5.410 -> **5.352** (-0.058 +- 0.025, 16 of 24, RTE 0.398 -> 0.395), 346x260 seeds
    0-23 4.161 -> **4.136** (-0.024 +- 0.013, 17 of 24), 240x180 3 s seeds 0-7 13.392 -> 13.236 (-0.16 +- 0.15, 4 of
    8); ARE within +-0.002 deg everywhere. Bundled demos (``--align none``): ``landing`` 6.556 -> 6.595,
    ``landing_fast`` 8.880 -> 8.972, ``landing_dynamic`` 6.131 -> 6.015 mm (its static twin 5.697 -> 5.626: 1.07x),
    none lost."""
    fused_painted_max_share: float = field(default=0.0, metadata={"min": 0.0, "max": 0.95, "step": 0.05, "unit": "ratio"})
    """In the fused modes, the painted points registration reads are thinned (an even stride) to at most this share of
    the registered points; the others are still refined (0 = off), ratio.

    Why: the painted refiner learns at the estimated pose, so the painted points carry the pose's error, and late in
    the simulated landing (the 'H' 27-37 % of the visible edges) they pull the field registration along the shift /
    tilt ridge: its Gauss-Newton step from the TRUE pose in 1.6-2 s, split by point class (``/tmp/s40/tr40/blame.py``),
    is the H's up to 24 mm on the worst seeds (43: camera x +23.9 mm / tilt about y -6.6 mrad; 27, 24 alike), the
    pad's rims' +3.6 to +5.7 mm in camera y on every seed, the rest's within 2.5 mm. Measured (``full``, 2 s landing
    from ground truth, built maps, CLI path paired per seed against main's defaults, ``/tmp/s40/tr40`` ``run.sh``,
    ``cmp.py``, ``cfg/pc*.yaml``; the painted share of the registered points grows 0.07 -> 0.26 over 0.5-2 s): 240x180
    seeds 0-23 4.934 mm -> 0.2: 4.914 (-0.020 +- 0.015, 14 of 24 better; ARE unchanged), held-out seeds 24-47 5.352 ->
    5.325 (-0.026 +- 0.016, 13 of 24; ARE 0.0624 -> 0.0620, 17 of 24); 0.1: seeds 0-18 4.782 -> 4.884 (+0.102 +- 0.063,
    8 of 19): what the H's pull costs, its lines' information buys back. With 0.2, 346x260 seeds 0-23 4.136 -> 4.131
    (-0.006 +- 0.008, 14 of 24), 240x180 3 s seeds 0-7 13.236 -> 13.292 (+0.056 +- 0.051, 2 of 8): a consistent but
    small gain on the 2 s landings and not the 3 s one, so off."""
    fused_refine_max_share: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """In the fused modes, the painted points are refined only in updates where they are at most this share of the
    registered points, i.e. while the other edges anchor the pose the refiner learns them against (0 = always), ratio.
    On the simulated 240x180 landing their share grows from 0.07 at 0.5 s to 0.26 at the end (seed 43). Measured (as
    ``fused_painted_max_share``, ``cfg/rs*.yaml``): 240x180 seeds 0-23 4.934 mm -> 0.15: 4.908 (-0.027 +- 0.092, 14 of
    24 better), 0.2: 4.906 (-0.028 +- 0.096, 15 of 24; RTE 0.396 -> 0.399): within the noise, which freezing the 'H'
    for the last 0.5-0.9 s makes large per seed. Off."""
    fused_registration_shift: bool = True
    """In the fused modes, measure each painted point's step where registration reads the field: behind its projection
    by the lag floor (``registration.fused_lag_floor_px``) and, for registered points, their polarity trail, as
    :mod:`evpose.tracker.edge_offsets` does (off: at the projection, i.e. at the field's trailing minimum).

    Why (session 40, ``/tmp/s40/hb40`` ``blame2.py``, ``sum.py``; DIAGNOSTIC, 240x180 2 s seeds 0/3/17/24/27/43): the
    field registration's step from the TRUE pose in 1.6-2 s, split by point class, has the painted 'H' (as refined with
    main's defaults) pull camera x +23.2 / +15.5 mm on seeds 43 / 27 (y -11.3 on 24), RMS over the six seeds 15.3 mm;
    the same points put on the true H edges (same events, same field) pull 5.7 mm RMS (43: x -2.3, 27: -1.4, 24: y
    +0.6): the H's events are not what pulls, its learned positions are. Started from the true H (oracle map), the
    refiner moves every vertical H edge by +3 to +14 mm in world x on every seed (the H's pull 5.0 -> 8.4 mm RMS), and
    its own clipped step from the true pose at the true edges is +x on all 6 vertical edges and -y on 5 of 6 horizontal
    ones: the field's minimum trails the edge, which registration's lag floor and trail model and the refiner did not.

    Measured (``full``, 2 s landing from ground truth, built maps, CLI path paired per seed against main's defaults,
    ``/tmp/s40/hb40`` ``run.sh``, ``cmp.py``, ``cfg/rs.yaml``; mean ATE RMSE mm +- standard error, seeds better):
    240x180 seeds 0-23 4.934 -> 4.763 (-0.171 +- 0.044, 17 of 24; ARE 0.0592 -> 0.0587, RTE 0.396 -> 0.392), held-out
    seeds 24-47 5.352 -> 5.210 (-0.142 +- 0.026, 21 of 24; ARE 0.0624 -> 0.0618), 346x260 seeds 0-23 4.136 -> 4.118
    (-0.018 +- 0.013, 15 of 24), 240x180 3 s seeds 0-7 13.236 -> 13.301 (+0.065 +- 0.119, 4 of 8; RTE 0.761 -> 0.736,
    6 of 8). Bundled demos (``--align none``, ``/tmp/s40/hb40`` ``demo.sh``): ``landing`` 6.595 -> 6.554, ``landing_fast``
    8.972 -> 9.035, ``landing_dynamic`` 6.015 -> 6.011 mm (its static twin 5.626 -> 5.657: 1.06x), none lost. On since
    session 40 (the SLAM does not use this refiner)."""
    first_updates: int = field(default=10, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """For a point's first this many updates the gain is at least 1 / (updates it took part in) (a running mean
    from the start; 0 = the fixed gain throughout), updates.

    Seeds 0-3, 346x260 / 240x180: 0 / 5 / 10 / 20 / 40 gave 26.2 / 24.8 / 24.5 / 24.6 / 24.6 mm and
    33.4 / 31.1 / 31.1 / 31.2 / 31.2 mm (10 with gain 0.03 / 0.1: 24.2 / 25.6 and 31.9 / 32.2 mm)."""
    register_after_updates: int = field(default=10, metadata={"min": 0, "max": 1000, "step": 1, "unit": "updates"})
    """A painted point takes part in registration only once it has been refined in this many updates (0 = from
    the start); in ``stpe`` and (``hold_out_filtered``) ``stpe+filter``, not in ``full`` (see below), and only while
    the others make up at least half of the visible points (a view of mostly painted edges has nothing else to
    track), updates.

    The 'H' of the simulated landing enters the view only after ~0.5 s, its points 10 mm (median) and up to
    4 cm off, and for the first updates they pull the pose towards their errors while the refiner is still
    moving them; held out meanwhile, they are still refined (the field is sampled at every painted point in
    its box). ``stpe``, 2 s landing from ground truth, built map, mean ATE of seeds 0-3 at 346x260 / 240x180,
    ``motion_filter.measurement_anisotropy`` 0.2: 0 / 10 gave 14.68 / 21.41, 13.42 / 19.00 mm; with 0.3,
    0 / 5 / 10 / 20 / 40 / 80 gave 14.39 / 21.24, 13.78 / 18.55, 13.49 / 18.46, 13.44 / 20.13, 12.78 / 34.35,
    15.57 / 70.60 mm (the longer the 'H' is held out the later its points start to anchor the pose; 40 and 80
    lose one or all 240x180 seeds to a slide); 7 gave 13.67 / 18.01 mm. Bundled demo (``stpe``, ``--align none``,
    lost from ~2 s either way, anisotropy 0): 134.9 -> 129.7 mm ATE RMSE. For scale: the simulator's painted
    edges themselves (painted points moved onto the true edges, no refinement) gave 11.84 / 15.69 mm.
    Session 9, held out in the filtered modes too (kept in ``T_align``, skipped by registration only; not kept):
    seeds 0-3 ``full`` 7.77 / 9.40 -> 7.36 / 9.27 mm, ``stpe+filter`` 15.77 / 23.37 -> 14.90 / 19.59 mm, but the
    textured landing (seed 0, 346x260) ``stpe+filter`` 23.26 -> 25.94 mm (``full`` 10.08 -> 9.13) and every 4 s demo
    worse: ``full`` landing / fast / dynamic 15.81 / 23.81 / 15.64 -> 15.84 / 24.74 / 16.14 mm, ``stpe+filter``
    171.6 / 1579 / 61.9 -> 181.5 / 1600 / 65.6 mm. Session 16, ``full`` with the event registration (6.38 / 5.91 mm
    at 346x260 seeds 0-3 / 4-7, 7.25 / 8.49 at 240x180): held out for 10 updates 6.15 / 6.12, 7.14 / 8.94 mm; for
    ever 6.52 mm (346x260 seeds 0-3); not changed."""
    hold_out_filtered: bool = True
    """``register_after_updates`` in ``stpe+filter`` too: a held-out painted point keeps its patch in ``T_align``
    (the polarity filter's field shows the composed points' patches alone, so a point left out of them would never
    be refined) and its sign learning, and registration skips it (``full`` is left as it is).

    Why ``stpe+filter`` trailed ``stpe`` on the plain landing, most of it: this hold-out was ``stpe``'s alone (session
    14, 2 s landing from ground truth, mean ATE of seeds 0-7 at 346x260 / 240x180, ``/tmp/s14/filterorder/run.py``):
    ``stpe`` 12.03 / 14.20 mm, without its hold-out 12.89 / 15.11 mm; ``stpe+filter`` 13.67 / 15.03 mm, with it
    12.38 / 14.50 mm (composing ``stpe``'s registration set plus the held points' patches instead: 12.21 / 14.63), and
    with ``polarity.reopen_contradicted_unfused`` and ``edge_offsets.stpe_filter_field_lag_ms`` 6.0 (the defaults now)
    11.76 / 14.12 mm. Textured landing (346x260, 7 % of its map painted against 1 % on the plain one), seeds 0-3:
    ``stpe+filter`` 22.66 / 23.06 / 22.68 / 26.04 (mean 23.61) -> 24.61 / 22.03 / 23.71 / 25.02 mm (mean 23.84) with
    the defaults (seed 0 with the hold-out alone 24.60); ``stpe`` 27.36 / 24.29 / 28.32 / 31.05, ``full`` 7.43 / 9.90
    / 9.42 / 9.74 mm: the ordering holds on every seed. That puts ``stpe+filter`` level with
    ``stpe`` on the plain landing, not clearly ahead: with the update rate moved to 190 / 210 Hz (``rate_hz``) ``stpe``
    scores 11.75 / 11.66 and 14.20 / 13.95 mm, ``stpe+filter`` 11.77 / 11.82 and 14.34 / 14.22 mm (before: 13.58 /
    15.07 mm at 190 Hz); the map explains nearly every event there (10-14 % removed). The runs without the
    polarity filter's event filter (``polarity.event_filter`` off: per-point fields) are no reference here: the
    refiner and the edge offsets never run on them (18.80 / 23.01 mm). The same hold-out in ``full`` (not kept, no
    switch): seeds 0-3 / 4-7 6.15 / 6.12 mm against 6.38 / 5.91 at 346x260, 7.15 / 8.94 against 7.25 / 8.49 mm at
    240x180."""
    max_offset_m: float = field(default=0.05, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest distance a point may move from the map's position, metres (0.03: 26.2 / 33.6 mm, as 0.05)."""
    step_clip_px: float = field(default=0.25, metadata={"min": 0.01, "max": 5.0, "step": 0.05, "unit": "px"})
    """Largest step one update measures for one point, pixels (before ``gain``)."""
    inlier_threshold: float = field(default=0.7, metadata={"min": 0.05, "max": 1.0, "step": 0.01, "unit": "TDF"})
    """Only points whose field value is below this take part (their edge fired), TDF units."""
    min_gradient: float = field(default=0.05, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "TDF/px"})
    """Only points whose field slope along their projected normal is at least this take part, TDF per pixel."""
    max_curvature: float = field(default=0.005, metadata={"min": 0.0, "max": 1.0, "step": 0.001, "unit": "ratio"})
    """A point counts as painted if it has a brightness sign and its surface variation is below this (painted edges
    lie inside flat regions: median 0.0008 on the landing map against 0.07 for geometric edges), ratio.

    Session 39: 1.0 also refines every geometric point with a known brightness sign (28 k of the 97 k points of a
    240x180 landing map, the pad's rims among them), which gives up their anchoring: ``full``, 2 s landing from ground
    truth, built maps, paired against 0.005 (``/tmp/s39/tr39`` ``run.sh``, ``cmp.py``, ``cfg/mc1.yaml``): seeds 0-13
    +1.54 +- 0.41 mm, 24-47 5.352 -> 6.308 mm (+0.96 +- 0.31, 7 of 24 better)."""


def painted_points(contour_map: ContourMap, max_curvature: float) -> np.ndarray:
    """Indices of the map's painted-edge points: a known brightness sign, a flat surface and a known edge normal."""
    known_normal = np.any(contour_map.edge_normal != 0, axis=1)
    return np.flatnonzero((contour_map.brightness_sign != 0) & (contour_map.curvature < max_curvature) & known_normal).astype(np.int64)


@nb.njit(cache=True)
def _refine_kernel(points, idx, base, normals, offsets, seen, R_cw, t_cw, fx, fy, cx, cy, value, grad_u, grad_v, box,
                   gain, max_offset, clip_px, thr, min_grad, first_updates, gauge, use_gauge, tangents, twist, lag_s, floor_px,
                   extra):
    """One update of every painted point's offset, written into ``points`` (rows ``idx``); returns how many moved.
    With ``floor_px`` > 0 or a non-empty ``extra`` (per painted point, px) the field is sampled where registration
    reads it (:func:`evpose.tracker.registration_kernels._floor_shift`, ``tangents`` per painted point)."""
    shifted = floor_px > 0.0 or extra.shape[0] > 0
    Ju = np.zeros(6)
    Jv = np.zeros(6)
    r0, r1, c0, c1 = box[0], box[1], box[2], box[3]
    moved = 0
    for j in range(idx.shape[0]):
        i = idx[j]
        X, Y, Z = camera_point(points, i, R_cw, t_cw)
        if Z <= 1e-6:
            continue
        u = fx * X / Z + cx
        v = fy * Y / Z + cy
        if not (u >= c0 and v >= r0 and u <= c1 - 1.0 and v <= r1 - 1.0) or r1 - r0 < 2 or c1 - c0 < 2:
            continue
        # Image of the map normal: d(u, v) / d(metres along the normal).
        nx, ny, nz = normals[j, 0], normals[j, 1], normals[j, 2]
        dX = R_cw[0, 0] * nx + R_cw[0, 1] * ny + R_cw[0, 2] * nz
        dY = R_cw[1, 0] * nx + R_cw[1, 1] * ny + R_cw[1, 2] * nz
        dZ = R_cw[2, 0] * nx + R_cw[2, 1] * ny + R_cw[2, 2] * nz
        du = fx * (dX * Z - X * dZ) / (Z * Z)
        dv = fy * (dY * Z - Y * dZ) / (Z * Z)
        L = np.sqrt(du * du + dv * dv)
        if L < 1e-6:
            continue
        if shifted:
            # Registration reads this point's field behind its projection (lag floor, polarity trail): the edge is
            # where the field's minimum lies seen from there.
            iz = 1.0 / Z
            pux = fx * iz
            puz = -fx * X * iz * iz
            pvy = fy * iz
            pvz = -fy * Y * iz * iz
            fill_image_rows(X, Y, Z, pux, puz, pvy, pvz, Ju, Jv)
            su, sv = _floor_shift(tangents, j, R_cw, X, Y, Z, fx, fy, Ju, Jv, twist, lag_s, floor_px,
                                  extra[j] if extra.shape[0] else 0.0)
            u += su
            v += sv
            if not (u >= c0 and v >= r0 and u <= c1 - 1.0 and v <= r1 - 1.0):
                continue
        x0, y0, w00, w01, w10, w11 = _bilinear_weights(u, v, r1, c1)
        f = w00 * value[0, y0, x0] + w01 * value[0, y0, x0 + 1] + w10 * value[0, y0 + 1, x0] + w11 * value[0, y0 + 1, x0 + 1]
        gu = w00 * grad_u[0, y0, x0] + w01 * grad_u[0, y0, x0 + 1] + w10 * grad_u[0, y0 + 1, x0] + w11 * grad_u[0, y0 + 1, x0 + 1]
        gv = w00 * grad_v[0, y0, x0] + w01 * grad_v[0, y0, x0 + 1] + w10 * grad_v[0, y0 + 1, x0] + w11 * grad_v[0, y0 + 1, x0 + 1]
        gn = (gu * du + gv * dv) / L
        if f >= thr or abs(gn) < min_grad:
            continue
        step = -f * gn / (gn * gn + 0.01)
        if use_gauge:
            # Take out the pose-like part of this update's offsets, measured on the other edges (``gauge``, see
            # evpose.tracker.edge_offsets): the map must not learn the pose's error.
            ju = du / L
            jv = dv / L
            iz = 1.0 / Z
            pux = fx * iz
            puz = -fx * X * iz * iz
            pvy = fy * iz
            pvz = -fy * Y * iz * iz
            step -= (gauge[0] * (ju * (-puz * Y) + jv * (pvy * Z - pvz * Y)) + gauge[1] * (ju * (puz * X - pux * Z) + jv * (pvz * X))
                     + gauge[2] * (ju * (pux * Y) + jv * (-pvy * X)) + gauge[3] * (ju * (-pux)) + gauge[4] * (jv * (-pvy))
                     + gauge[5] * (ju * (-puz) + jv * (-pvz)))
        step = min(max(step, -clip_px), clip_px)
        seen[j] += 1
        g = gain
        if first_updates > 0 and seen[j] <= first_updates:
            g = max(gain, 1.0 / seen[j])
        off = offsets[j] + g * step / L
        offsets[j] = min(max(off, -max_offset), max_offset)
        for k in range(3):
            points[i, k] = base[j, k] + offsets[j] * normals[j, k]
        moved += 1
    return moved


_NO_GAUGE = np.zeros(6)
"""Placeholder gauge handed to :func:`_refine_kernel` when there is none (never read)."""


class PaintedEdgeRefiner:
    """Offsets of the painted points along their edge normals, applied to the registration's copy of the map."""

    def __init__(self, config: MapRefinementConfig, contour_map: ContourMap):
        self.config = config
        self.index = painted_points(contour_map, float(config.max_curvature))
        self._slot = np.full(len(contour_map), -1, dtype=np.int64)
        self._slot[self.index] = np.arange(self.index.size)
        """Per map point its row in ``index`` (-1: not painted)."""
        self._base = np.ascontiguousarray(contour_map.points[self.index], dtype=np.float64)
        n = np.asarray(contour_map.edge_normal[self.index], dtype=np.float64)
        self._tangents = np.ascontiguousarray(np.cross(np.asarray(contour_map.plane_normal[self.index], dtype=np.float64), n))
        """Edge direction per painted point (as the tracker's), for ``fused_registration_shift``."""
        self._normals = np.ascontiguousarray(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12))
        self.offsets = np.zeros(self.index.size)
        """Current offset of each painted point along its unit edge normal, metres."""
        self.seen = np.zeros(self.index.size, dtype=np.int64)
        """Updates each painted point took part in."""
        self._held = np.zeros(len(contour_map), dtype=np.bool_)
        """Per map point: a painted point not yet refined in ``register_after_updates`` updates (see :meth:`held_out`)."""
        self._update_held()

    def _update_held(self) -> None:
        n = int(self.config.register_after_updates)
        if n > 0 and self.config.enabled and self.config.gain > 0:
            self._held[self.index] = self.seen < n

    def held_out(self) -> np.ndarray | None:
        """(N,) bool over the map's points: painted points registration should skip for now, or None if none is."""
        return self._held if self.index.size and int(self.config.register_after_updates) > 0 and self._held[self.index].any() else None

    def painted_values(self, used: np.ndarray, values: np.ndarray) -> np.ndarray:
        """(n,) per painted point: ``values`` of the map points ``used`` that are painted, 0 for the others."""
        out = np.zeros(self.index.size)
        slot = self._slot[used]
        keep = slot >= 0
        out[slot[keep]] = values[keep]
        return out

    def update(self, points: np.ndarray, field_, T_world_cam_field: np.ndarray, K: np.ndarray, gauge: np.ndarray | None = None,
               twist: np.ndarray | None = None, lag_s: float = 0.0, floor_px: float = 0.0, trail_px: np.ndarray | None = None) -> int:
        """Refine with one update's field (combined slot), the pose it shows (lag included); returns the points moved.
        ``gauge`` (6,): a pose change (right-perturbation tangent) whose image motion is taken out of every step.
        With ``twist`` (6,) body twist per second and ``floor_px`` > 0 or ``trail_px`` ((n,) per painted point, px), the
        field is read where registration reads it (``lag_s`` the lag the field pose carries)."""
        if self.index.size == 0 or not self.config.enabled or self.config.gain <= 0:
            return 0
        tg, xi, extra, floor = _NO_TANGENTS, _NO_TWIST, _NO_EXTRA, 0.0
        if twist is not None and (floor_px > 0 or trail_px is not None) and np.isfinite(twist).all():
            tg, xi, floor = self._tangents, np.ascontiguousarray(twist, dtype=np.float64).reshape(6), float(floor_px)
            if trail_px is not None:
                extra = np.ascontiguousarray(trail_px, dtype=np.float64).reshape(self.index.size)
        T_cw = inv(np.asarray(T_world_cam_field, dtype=np.float64))
        c = self.config
        moved = int(_refine_kernel(points, self.index, self._base, self._normals, self.offsets, self.seen, np.ascontiguousarray(T_cw[:3, :3]),
                                  np.ascontiguousarray(T_cw[:3, 3]), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
                                  field_.value, field_.grad_u, field_.grad_v, field_.box, float(c.gain), float(c.max_offset_m),
                                  float(c.step_clip_px), float(c.inlier_threshold), float(c.min_gradient), int(c.first_updates),
                                  _NO_GAUGE if gauge is None else np.ascontiguousarray(gauge, dtype=np.float64), gauge is not None,
                                  tg, xi, float(lag_s), floor, extra))
        if moved:
            self._update_held()
        return moved

    def apply(self, points: np.ndarray) -> None:
        """Write the current offsets into ``points`` (after a restore)."""
        if self.index.size:
            points[self.index] = self._base + self.offsets[:, None] * self._normals

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        return np.copy(self.offsets), np.copy(self.seen)

    def restore(self, state: tuple[np.ndarray, np.ndarray]) -> None:
        self.offsets, self.seen = np.copy(state[0]), np.copy(state[1])
        self._update_held()
