"""Edge tracking for event-only maps starved of point tracks: the pose from 1-D across-the-edge residuals and a motion prior.

Indoors an event-only map loses its KLT tracks while the camera yaws past vertical edges
(:mod:`evpose.slam.event_coasting`): the events place a point on such an edge across the edge but not along it, so
KLT slides and its tracks fail the forward-backward test, and the map coasts on its own recent motion. Here the map's
points are measured the way the events can measure them: each point's template (cut from its newest keyframe MCI,
:mod:`evpose.slam.projection_search`) is searched in the current MCI on a line through its predicted projection along
the template's edge normal (structure tensor), by normalised cross-correlation; the match gives a 1-D residual, the
signed distance across the edge. Along the edge the point is free; the pose components no edge constrains (pitch and
the vertical translation while only vertical edges are seen) come from a Gaussian prior at the coasting prediction
(the map's recent rotation rate and camera-frame velocity held, or the visual gyro's rotation), solved together by
Levenberg-Marquardt with Huber weights. The MCI counts as tracked from the events (status ``ok``) when enough
measurements agree with the solved pose and the edges pin the pose well beyond the prior in at least one direction
(:attr:`EdgeTrackingConfig.min_info_gain`). Event-inertial maps never use it.

Measured (session 19, ``/tmp/s19/lines9``: ``exp.py`` as session 18's harness, ``pair.py`` pairs runs, ``diag.py`` logs
each attempt against the truth, ``acc.py`` splits the per-map aligned errors by how each pose was made). Indoor seeds
0-7, event-only, defaults: ATE 6.83 %, tracked 92.8 %, from the events 40.7 %, 30 maps.

- First try, residuals from the MCI's edge distance field (the visual gyro's ridge pixels) at each map point's
  projection: of a median 81.5 map points in view only 2 lay within 1 px of a ridge (seeds 0, 2, 4; 1 of 290 attempts
  accepted with ``min_points`` 12); with the visual gyro's rotation as the prior, the aligned rotation was worse than
  the prior's within 15 ms of the last PnP pose (0.42 -> 2.15 deg against the truth). Replaced by the template search.
- Why so few measurements: most map points project where the current MCI has no events at all (template search, seed
  0: best NCC on the search line a median 0; at least 0.8 for 4 %, 0.6 for 10 %): while the camera yaws, points on
  horizontal edges and corners make no events, and most points were born on noise (:mod:`evpose.slam.event_coasting`).
  A median 5 points per attempt are measured (``min_ncc`` 0.7).
- ``min_points`` 4 / 6 / 8 / 10 (``min_ncc`` 0.7): ATE 9.86 / 7.95 / 6.45 / 7.89 %, from the events 56.4 / 49.2 / 47.1 /
  47.7 %, maps 25 / 29 / 29 / 30, tracked 93.3 / 94.9 / 95.7 / 92.5 %. ``min_points`` 4 with the visual gyro 7.89 % /
  58.9 % / 26 maps (CPU per MCI median ~31 ms); 8 with it 5.52 % / 36.0 % / 33 maps (the gyro's split into more maps).
  4 without resetting the coast's clock (``resets_coast`` off): 10.33 % / 60.9 % / 27 maps.
- ``min_points`` 8, ``min_ncc`` 0.7 over 32 runs (the defaults and the neutral nudges ``ba_huber_px`` 1.9 / 2.1 and
  ``reprojection_threshold_px`` 2.4): ATE 7.42 -> 7.48 % (paired +0.06 +- 0.49 s.e., better in 18), from the events
  42.6 -> 50.0 % (+7.5 +- 2.1, higher in 26), tracked 92.9 -> 94.7 %, maps 118 -> 114, median RPE 0.0385 -> 0.0346 m/m,
  CPU per MCI median 16.4 -> 22.0 ms (not paired). Per seed, defaults (ATE % / from the events % / maps, before ->
  after): 0 8.24/43.2/3 -> 7.29/45.4/3, 1 5.61/31.0/4 -> 3.46/33.3/4, 2 3.10/40.8/4 -> 6.59/44.8/4, 3 9.08/42.1/3 ->
  6.59/53.3/4, 4 7.37/54.4/3 -> 5.34/48.2/4, 5 5.24/21.7/6 -> 8.64/47.7/4, 6 6.63/46.6/4 -> 6.45/48.3/3, 7 9.34/46.0/3
  -> 7.23/55.6/3. Held-out seeds 8-11: 7.98 -> 8.89 %, from the events 44.3 -> 59.5 %, maps 14 -> 11.
  The edge-tracked poses are no better than coasted ones: per map aligned to the truth (seeds 0-3), rotation error
  median 8.63 deg at edge-tracked MCIs, 7.65 at coasted ones, 5.13 at PnP-tracked ones; the few measurements agree
  with the prediction to within a pixel, so the solve hardly moves it. The share tracked from the events rises mostly
  because maps live longer on these MCIs, not because the edges correct the pose.
- With a local BA on each edge-tracked keyframe (``adjust_keyframes``), 32 runs: ATE 7.42 -> 9.04 % (+1.62 +- 0.66),
  from the events 51.6 %, maps 108. With ``sigma_rotation_deg`` 0.5: 8.36 % (+0.94 +- 0.50), 52.9 %, 109 maps.
  Without resetting the coast's clock (``resets_coast`` off; maps end ``coast_s`` after their last PnP pose as
  before): 7.80 % (+0.39 +- 0.51), 52.2 %, 121 maps, median RPE 0.0378 m/m.
- CPU per MCI (thread time; indoor seeds 0-1, defaults and edge tracking alternated twice in one process, ``cpu.py``):
  median 14.8 -> 17.8 ms, mean 19.0 -> 19.6 ms; an edge-tracked MCI's tracking step median 21.5 ms.
- Landing event-only seeds 0-11 with it on: bit-identical figures (1.85 %; their maps never starve there), and
  E-I-C2 landing seeds 0-1 too (event-inertial maps bridge on the IMU and never reach it).

Off by default: the ATE does not improve. What it lacks is measurements: a map of points on lines (born on the
vertical edges the camera sweeps past, free along them) rather than KLT corners, most of which never fire again.

A semi-dense edge map does not give the missing measurements either (session 21, ``semidense9``, not integrated;
scripts in ``/tmp/s21/semidense9``: ``cache_runs.py`` keeps each MCI and pose of a default event-only run,
``emvs.py`` builds the map and aligns, ``oracle.py`` / ``summ.py`` measure, ``valley.py`` the conditioning; logs
``sweep8.log``, ``sweep8_local.log``). The map: EMVS (Rebecq et al. 2018) over a 0.3 s stretch of events, one
reference view in its middle, 100 inverse-depth planes, the per-pixel ray-density maximum kept where it beats its
5x5 Gaussian mean by 1.5 votes and the 90th percentile, 5x5 median depth (about 1120 points at landing, 470 indoors).
Each MCI of the next 0.3 s was aligned in 6 DoF by Levenberg-Marquardt to the distance field of its ridge crests (4 %
of the pixels; Huber 0.5 px, truncated at 4 px), free along the edges. Simulated seeds 0-7, rotation error median /
RMS:

- Map from the true poses, alignment started at the truth: it moves the pose 0.41 / 0.71 deg (landing, MCIs within
  0.1 s of the map; 0.57 / 1.62 over 0.3 s) and 0.83 / 1.56 indoors (1.25 / 6.99). Started 1.5 deg off: 0.65 / 1.03
  and 1.20 / 2.27. Rotation between consecutive MCIs: 0.50 / 1.00 deg at landing against the PnP's 0.73 / 1.32.
- Rotation alone (translation held): at the true translation 0.06 / 0.10 deg at landing and 0.26 / 0.65 indoors
  (within 0.1 s), but held 1 % of the depth off (and started 1.5 deg off) 0.47 / 0.81 and 0.81 / 1.12: the
  weakest direction of the alignment's Hessian at the truth trades rotation about x / y against sideways
  translation (rotation share 0.69), its per-pixel std 11x (landing) / 19x (indoors) the strongest's (seeds 0-3).
  One image pins the pose no better than the PnP.
- Map from the SLAM's own poses (a Sim(3) of the stretch's poses onto the truth, so later errors are drift): from
  the PnP pose, landing rotation 1.94 -> 1.80 deg (within 0.1 s), 2.54 -> 2.61 over 0.3 s, translation 18.8 ->
  21.6 cm; consecutive MCIs 0.73 / 1.32 -> 1.26 / 2.19 deg (rotation only: 0.88 / 1.57); indoors 9.57 -> 10.49 deg.
  The map's own pose errors blur it: it pulls the true pose 1.47 deg off.
- Not the limit: an oracle event image (events of +-10 ms warped with the true poses through the plane at the map's
  median depth) instead of the MCI (0.41 / 0.81 deg from the truth), 300 depth planes, ridge shares 2-8 %, a top-12 %
  mask, Canny edges, Huber 0.5-2 px and truncation 4-10 px (0.29-0.55 deg median from the truth, none better).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.geometry import project


@dataclass
class EdgeTrackingConfig:
    """Event-only pose tracking from map points on the MCI's edges when too few point tracks survive."""

    enabled: bool = False
    """A starved (or PnP-rejected) event-only map tries this before coasting; on success the MCI is tracked (status
    ``ok``). Off: indoors it raises the share tracked from the events by 7.5 points at the same ATE, and its poses are
    no better than the coast's (figures in the module docstring)."""
    sigma_rotation_deg: float = field(default=1.0, metadata={"min": 0.01, "max": 20.0, "step": 0.05, "unit": "deg"})
    """Sigma of the motion prior's rotation about each camera axis, degrees (0.5: indoor 32 runs ATE 7.48 -> 8.36 %)."""
    sigma_translation_ratio: float = field(default=0.01, metadata={"min": 0.0001, "max": 0.5, "step": 0.001, "unit": "ratio"})
    """Sigma of the motion prior's translation along each camera axis, as a share of the median depth of the points in
    view, ratio."""
    search_px: int = field(default=8, metadata={"min": 1, "max": 30, "step": 1, "unit": "px"})
    """Each point's template is searched this far either side of its predicted projection along its edge normal, pixels."""
    min_ncc: float = field(default=0.7, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "NCC"})
    """Smallest normalised cross-correlation accepted on the search line, NCC."""
    max_second_ratio: float = field(default=0.9, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """The best score more than two pixels from the best match must stay below this share of it (uniqueness), ratio."""
    min_straightness: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Templates whose structure tensor is less elongated than this (1 - smaller / larger eigenvalue) are not
    measured, ratio."""
    huber_px: float = field(default=1.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """Huber threshold of the across-edge distance, pixels."""
    inlier_px: float = field(default=1.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """A measurement agrees with the solved pose when the point projects this close to it across the edge, pixels."""
    min_points: int = field(default=8, metadata={"min": 3, "max": 500, "step": 1, "unit": "points"})
    """Fewer map points agreeing across their edges than this and the MCI is not tracked (4 / 6 / 8 / 10 measured in
    the module docstring), points."""
    min_inlier_ratio: float = field(default=0.2, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """At least this share of the measured map points must agree with the solved pose, ratio."""
    min_info_gain: float = field(default=4.0, metadata={"min": 1.0, "max": 1000.0, "step": 0.5, "unit": "ratio"})
    """The edges must shrink the prior's variance at least this many times in the best-measured pose direction; a
    pose the edges hardly measure is a coast, not a track, ratio."""
    iterations: int = field(default=10, metadata={"min": 1, "max": 100, "step": 1, "unit": "iterations"})
    """Levenberg-Marquardt iterations, iterations."""
    max_span_s: float = field(default=0.4, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "s"})
    """Longest stretch of edge-tracked MCIs since the last MCI tracked from point tracks (PnP), seconds."""
    resets_coast: bool = True
    """An edge-tracked MCI restarts the coast's clock (``TrackingConfig.coast_s``) as a PnP-tracked one does (off:
    indoor 32 runs ATE 7.48 -> 7.80 %, maps 114 -> 121)."""
    adjust_keyframes: bool = False
    """The keyframe made at an edge-tracked MCI gets a local BA (off: none, as for a coasted one; on: indoor 32 runs
    ATE 7.48 -> 9.04 %)."""
    border_px: int = field(default=4, metadata={"min": 1, "max": 50, "step": 1, "unit": "px"})
    """Projections this close to the image border are left out, pixels."""


@dataclass
class EdgePose:
    ok: bool
    T_cw: np.ndarray | None
    """Solved ``T_cam_world`` (4, 4), also when not accepted (None without points in view)."""
    n_view: int = 0
    """Map points measured across their edges."""
    n_on_edge: int = 0
    """Of them, within ``inlier_px`` across the edge at the solved pose."""
    info_gain: float = 0.0
    """Largest ratio of prior to posterior variance over pose directions (whitened by the prior)."""
    inliers: np.ndarray | None = None
    """Mask of the measurements within ``inlier_px`` across their edge at the solved pose (N,)."""
    reason: str = ""


def edge_normal(patch: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit normal (2,) of the template's dominant edge (structure tensor) and its straightness (1 - smaller / larger
    eigenvalue: 1 for a straight edge, 0 for an isotropic corner or blob)."""
    p = patch.astype(np.float32)
    gx = cv2.Sobel(p, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(p, cv2.CV_32F, 0, 1, ksize=3)
    J = np.array([[float((gx * gx).sum()), float((gx * gy).sum())], [float((gx * gy).sum()), float((gy * gy).sum())]])
    ev, vec = np.linalg.eigh(J)
    return vec[:, 1], (1.0 - ev[0] / ev[1]) if ev[1] > 1e-9 else 0.0


def search_across(img8: np.ndarray, patch: np.ndarray, uv: np.ndarray, n: np.ndarray, cfg: EdgeTrackingConfig) -> float | None:
    """Offset (px) along ``n`` from ``uv`` at which ``patch`` matches ``img8`` best, searched on a line (None when no
    strong, unique match): along an edge every position matches, across it one does."""
    size = patch.shape[0]
    r = size // 2
    h, w = img8.shape
    offs = np.arange(-cfg.search_px, cfg.search_px + 1, dtype=np.float64)
    centres = uv[None, :] + offs[:, None] * n[None, :]
    if not ((centres[:, 0] >= r) & (centres[:, 0] < w - r - 1) & (centres[:, 1] >= r) & (centres[:, 1] < h - r - 1)).all():
        return None
    x0, y0 = np.floor(centres.min(axis=0)).astype(int) - r
    x1, y1 = np.ceil(centres.max(axis=0)).astype(int) + r + 2
    if not img8[max(y0, 0):y1, max(x0, 0):x1].any():
        return None  # no event near the line (most map points indoors: their edges make no events while the camera yaws)
    t = patch.astype(np.float32).ravel()
    t = t - t.mean()
    tn = float(np.linalg.norm(t))
    if tn < 1e-6:
        return None
    cut = np.stack([cv2.getRectSubPix(img8, (size, size), (float(c[0]), float(c[1]))).astype(np.float32).ravel() for c in centres])
    cut -= cut.mean(axis=1, keepdims=True)
    score = cut @ t / np.maximum(np.linalg.norm(cut, axis=1) * tn, 1e-6)
    i = int(np.argmax(score))
    best = float(score[i])
    if best < cfg.min_ncc or i == 0 or i == len(score) - 1:
        return None  # too weak, or the flank of a peak outside the search line
    away = np.abs(offs - offs[i]) > 2.0
    if away.any() and float(score[away].max()) >= cfg.max_second_ratio * best:
        return None
    a, b, c = score[i - 1], score[i], score[i + 1]
    den = a - 2.0 * b + c
    return float(offs[i] + (np.clip(0.5 * (a - c) / den, -0.5, 0.5) if den < 0 else 0.0))


def measure_across_edges(img8: np.ndarray, K: np.ndarray, T_cw: np.ndarray, Xw: np.ndarray, patches: list[np.ndarray],
                         cfg: EdgeTrackingConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """1-D measurements of the points ``Xw`` (N, 3) with templates ``patches`` around their projections by ``T_cw``:
    (indices of the measured points (M,), their measured pixels (M, 2), the edge normals there (M, 2))."""
    h, w = img8.shape
    proj, z = project(K, T_cw, Xw)
    b = cfg.border_px
    inside = (z > 0) & (proj[:, 0] >= b) & (proj[:, 0] < w - b) & (proj[:, 1] >= b) & (proj[:, 1] < h - b)
    idx, uv, nrm = [], [], []
    for i in np.flatnonzero(inside):
        if not patches[i].any():
            continue
        n, straight = edge_normal(patches[i])
        if straight < cfg.min_straightness:
            continue
        s = search_across(img8, patches[i], proj[i], n, cfg)
        if s is not None:
            idx.append(int(i))
            uv.append(proj[i] + s * n)
            nrm.append(n)
    if not idx:
        return np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, 2))
    return np.array(idx, np.int64), np.array(uv), np.array(nrm)


def _prior_error(T_cw: np.ndarray, T_pred_cw: np.ndarray) -> np.ndarray:
    """6-vector (rotation vector, translation) of ``T_cw`` relative to the prediction, in the camera frame."""
    D = T_cw @ np.linalg.inv(T_pred_cw)
    return np.concatenate([Rotation.from_matrix(D[:3, :3]).as_rotvec(), D[:3, 3]])


def _huber_cost(r: np.ndarray, k: float) -> float:
    a = np.abs(r)
    return float(np.sum(np.where(a <= k, 0.5 * a * a, k * (a - 0.5 * k))))


def _across(K: np.ndarray, T_cw: np.ndarray, Xw: np.ndarray, uv: np.ndarray, nrm: np.ndarray):
    """Camera points and signed across-edge residuals ``n . (projection - measurement)`` (px)."""
    Xc = Xw @ T_cw[:3, :3].T + T_cw[:3, 3]
    z = np.maximum(Xc[:, 2], 1e-9)
    proj = np.c_[K[0, 0] * Xc[:, 0] / z + K[0, 2], K[1, 1] * Xc[:, 1] / z + K[1, 2]]
    return Xc, np.sum(nrm * (proj - uv), axis=1)


def solve_pose_across_edges(K: np.ndarray, Xw: np.ndarray, uv: np.ndarray, nrm: np.ndarray, T_pred_cw: np.ndarray,
                            cfg: EdgeTrackingConfig) -> EdgePose:
    """Pose ``T_cam_world`` from 1-D across-edge measurements (points ``Xw`` (N, 3) measured at ``uv`` (N, 2) along the
    normals ``nrm`` (N, 2)) and a Gaussian prior at ``T_pred_cw`` (Levenberg-Marquardt, Huber weights)."""
    T = np.array(T_pred_cw, np.float64)
    n = len(Xw)
    if n < cfg.min_points:
        return EdgePose(False, T, n, reason=f"{n} map points measured across edges < {cfg.min_points}")
    fx, fy = K[0, 0], K[1, 1]
    depth = float(np.median((Xw @ T[:3, :3].T + T[:3, 3])[:, 2]))
    sig = np.r_[np.full(3, np.radians(cfg.sigma_rotation_deg)), np.full(3, cfg.sigma_translation_ratio * max(depth, 1e-9))]
    Wp = 1.0 / sig**2

    def cost(T_):
        _, r = _across(K, T_, Xw, uv, nrm)
        e = _prior_error(T_, T_pred_cw)
        return _huber_cost(r, cfg.huber_px) + 0.5 * float(e @ (Wp * e))

    c, lam, Hv = cost(T), 1e-3, np.zeros((6, 6))
    for _ in range(cfg.iterations):
        Xc, r = _across(K, T, Xw, uv, nrm)
        x, y, z = Xc[:, 0], Xc[:, 1], np.maximum(Xc[:, 2], 1e-9)
        g3 = np.stack([nrm[:, 0] * fx / z, nrm[:, 1] * fy / z, -(nrm[:, 0] * fx * x + nrm[:, 1] * fy * y) / z**2], axis=1)
        J = np.c_[np.cross(Xc, g3), g3]  # d residual / d (w, t) for Xc -> exp(w) Xc + t
        a = np.abs(r)
        wts = np.where(a <= cfg.huber_px, 1.0, cfg.huber_px / np.maximum(a, 1e-12))
        Hv = (J * wts[:, None]).T @ J
        e = _prior_error(T, T_pred_cw)
        H = Hv + np.diag(Wp)
        g = (J * wts[:, None]).T @ r + Wp * e
        improved = False
        for _ in range(6):
            try:
                step = -np.linalg.solve(H + lam * np.diag(np.diag(H)), g)
            except np.linalg.LinAlgError:
                return EdgePose(False, T, n, reason="singular normal equations")
            D = np.eye(4)
            D[:3, :3] = Rotation.from_rotvec(step[:3]).as_matrix()
            D[:3, 3] = step[3:]
            T_new = D @ T
            c_new = cost(T_new)
            if c_new < c:
                T, c, lam, improved = T_new, c_new, max(lam / 10.0, 1e-7), True
                break
            lam *= 10.0
        if not improved:
            break
    _, r = _across(K, T, Xw, uv, nrm)
    inl = np.abs(r) < cfg.inlier_px
    # Whitened by the prior, the largest eigenvalue of the edges' information says how much better than the prior the
    # best-measured pose direction is known (variance ratio 1 + eigenvalue).
    s = np.sqrt(1.0 / Wp)
    gain = 1.0 + float(np.linalg.eigvalsh(Hv * np.outer(s, s))[-1])
    res = EdgePose(False, T, n, int(inl.sum()), gain, inliers=inl)
    if res.n_on_edge < cfg.min_points or res.n_on_edge < cfg.min_inlier_ratio * n:
        res.reason = f"{res.n_on_edge} of {n} measured map points agree across their edges"
    elif gain < cfg.min_info_gain:
        res.reason = f"edges measure the pose {gain:.1f}x the prior < {cfg.min_info_gain}"
    else:
        res.ok = True
    return res
