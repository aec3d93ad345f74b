"""Motion-compensated images (paper Algorithm 2): warp hypotheses H1-H4 (and our H5), local-STD scoring, selection.

Every hypothesis is a constant velocity over the window (``psi = Log(theta)/dT``);
events are moved to the window's reference time (its last timestamp, or
``MciConfig.reference_fraction`` of the way to it) with ``Exp(psi dt)``,
sampled once per time slice. A Sim(2) motion and an SE(3) motion seen through a
fronto-parallel plane at one depth are both pixel homographies, so one splat
kernel renders them all.

An 8-DoF homography fitted to the tracks (RANSAC, 1.5 px) as H2, its per-slice
powers by matrix exponential, made the simulated landing worse (event-only,
seeds 0-11, reference fraction 1.0: mean ATE 3.16 -> 5.43 %, tracked at least
68.6 %): over the few pixels of motion a window spans, its projective terms
follow the track noise.

Session 26 (``/tmp/s26/speed26``), the main thread's CPU: the MCI stage spent 9-10 ms of the landing's 29-31 ms per
MCI in numpy and scipy overhead around small arrays, not in the splats. Now in numba or batched, each bit for bit the
code it replaced (tests named ``test_*_kernels.py`` / ``test_geometry_rotvec.py`` keep that code as the reference):
the sharpness score and 8-bit scaling (:mod:`evpose.slam.event_image`), :func:`se3_homographies` (one rotation call
for all slices, 0.55 -> 0.03 ms), :func:`fit_average_depth`'s median search (0.7 -> 0.1-0.3 ms), H5's projection
(:func:`evpose.slam.parallax_warp.project_moved`, the einsum 73 -> 5-24 us; its twist fit 1.6 -> 0.5 ms a call) and
every warp's rotation matrices (:func:`evpose.slam.geometry.rotvec_matrices`, scipy's arithmetic without its 10-15 us
a call). Same trajectories, tracks, hypotheses, scores and MCIs as main (``ident.py`` / ``ident2.py``: landing
event-only seeds 0-11, event-inertial 0 and 2, E-I-C2 1; indoor event-only 0-3, E-I-C2 1; 22 runs hashed; and
``/tmp/s22/lead/exp.py`` landing seeds 0-23, ``main_land.json`` / ``new_land.json``: every seed's ATE, tracked share
and maps the same, mean 1.44 %, 24 of 24 within 2 %; the whole run's CPU, tiny frames included, 3.84 -> 3.42 s mean).
CPU per MCI
(``mci_cpu`` + ``tracking_cpu``; ``benchloop.sh`` runs ``bench1.py``, main and this code in strictly alternating
processes, ABBA, each the second run of its process; ``benchsum.py``; a loaded machine, so main's own figure is above
session 25's 28.6 ms). These kernels alone (four runs per seed, ``bench_r2/r3.jsonl``): landing seeds 0-3 median of the
runs' medians 31.3 -> 26.6 ms (median of the runs' means 37.0 -> 31.5; per seed -4.1 to -7.0 ms), the MCI stage alone
9.7 -> 5.0 ms; indoor seeds 0-1 16.4 -> 12.8 ms (means 20.2 -> 16.5), MCI stage 5.3 -> 2.3 ms. With KLT's unread error
pass dropped as well (:data:`evpose.slam.features.KLT_NO_ERROR`; four runs per seed, ``bench_r4/r5.jsonl``): landing
31.1 -> 25.8 ms (means 36.2 -> 30.8; per seed -3.8 to -6.5 ms), MCI stage 9.6 -> 5.0 ms; indoor 16.4 -> 12.2 ms (means
19.7 -> 16.0), MCI stage 5.2 -> 2.2 ms. What is left per landing MCI
(``split.py``, seed 0): the fine-grid KLT about 9 ms and the re-finding KLT about 5 ms (OpenCV, whose Python binding
cannot take a pyramid built once per image, so each call rebuilds both), a keyframe with its local BA about 22 ms (one
MCI in three), PnP 1.6 ms, the MCI stage about 4.6 ms (splats and blurs 2.2, H5 1.7).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import cv2
import numba as nb
import numpy as np

from evpose.slam.config import EventImageConfig, FeatureConfig, MciConfig
from evpose.slam.event_image import event_image, local_std_score, to_uint8
from evpose.slam.reconstruction_window import ReconstructionWindow
from evpose.slam.fine_grid import fine_to_uint8
from evpose.slam.geometry import rotvec_matrices
from evpose.slam.parallax_warp import depth_field, fit_twist, sample_depth, warp_events
from evpose.slam.window_fit import fit_twist_rate, whole_span_s


class Hypothesis(str, enum.Enum):
    """The warps of Algorithm 2."""

    H1_MAP_DEPTH = "H1"
    """SE(3) constant velocity from the tracked poses, median depth of the map."""
    H2_SIM2 = "H2"
    """Sim(2) fitted to the window's feature tracks."""
    H3_POSE_PRIOR = "H3"
    """SE(3) from the IMU / last-pose prior, average depth fitted to the feature tracks (eq. 5)."""
    H4_NONE = "H4"
    """No compensation: the plain event histogram."""
    H5_PARALLAX = "H5"
    """SE(3) fitted to the window's feature tracks, each event at the depth of its nearest map point
    (:mod:`evpose.slam.parallax_warp`)."""


@dataclass
class MotionPrior:
    """What the rest of the system knows about the camera motion when a window is reconstructed."""

    omega: np.ndarray | None = None
    """Angular velocity of the camera in its own frame, rad/s (3,): IMU gyro or last poses."""
    velocity: np.ndarray | None = None
    """Linear velocity of the camera in its own frame, map units/s (3,), from the last poses."""
    map_depth: float | None = None
    """Median depth of the map points in the current view, map units."""
    point_uv: np.ndarray | None = None
    """Map points of the tracks projected at the last tracked pose, px (N, 2): H5's depth samples."""
    point_depth: np.ndarray | None = None
    """Their depths at that pose, map units (N,)."""


@dataclass
class MciResult:
    """The dispatched image and what was tried."""

    t_us: int
    """Reference time of the MCI (the window's last event, or ``MciConfig.reference_fraction`` of the way to it), us."""
    image: np.ndarray
    """Selected MCI, float32 (H, W)."""
    image8: np.ndarray
    """Its 8-bit form, uint8 (H, W)."""
    hypothesis: Hypothesis
    scores: dict[str, float] = field(default_factory=dict)
    """Mean local STD per tried hypothesis ("H1".."H5")."""
    n_events: int = 0
    sim2: np.ndarray | None = None
    """Fitted Sim(2) motion over the track interval (3x3 px), kept as the next prior."""
    depth: float | None = None
    """Scene depth of the H3 fit, map units."""
    candidates: dict = field(default_factory=dict, repr=False)
    """Every rendered hypothesis ("H1".."H5") -> float32 image: the tracker may prefer the previous MCI's hypothesis."""
    splats: dict = field(default_factory=dict, repr=False)
    """Every rendered hypothesis -> its :class:`Splat`, to render it again on a finer grid (:meth:`fine_image`)."""
    t_by_hypothesis: dict = field(default_factory=dict, repr=False)
    """Reference times of the hypotheses whose image is not stamped at the window's (``MciConfig.unwarped_own_events``:
    H4) -> us; the others are stamped at the window's, as ``t_us`` is when they win."""

    def time_of(self, hypothesis: str) -> int:
        """Reference time of ``hypothesis``'s image, us (:attr:`t_by_hypothesis`)."""
        return self.t_by_hypothesis.get(hypothesis, self.t_by_hypothesis.get("window", self.t_us))

    def fine_image(self, hypothesis: str, scale: float, sigma_px: float) -> np.ndarray:
        """``hypothesis``'s image on the grid ``scale`` times finer with a splat of ``sigma_px`` sensor pixels, float32
        (``FeatureConfig.klt_upsample``)."""
        return self.splats[hypothesis].render(scale, sigma_px)

    def fine8(self, hypothesis: str, features: FeatureConfig) -> np.ndarray | None:
        """``hypothesis``'s image on the grid KLT runs on, 8 bits (None when ``FeatureConfig.klt_upsample`` is off)."""
        if features.klt_upsample <= 1.0:
            return None
        return fine_to_uint8(self.fine_image(hypothesis, features.klt_upsample, features.klt_upsample_sigma_px),
                             int(features.klt_upsample_scale_stride))


@dataclass
class Splat:
    """How one hypothesis's image is rendered: the events (raw, or already warped for H5), their weights and warps."""

    x: np.ndarray
    y: np.ndarray
    p: np.ndarray | None
    width: int
    height: int
    idx: np.ndarray | None = None
    H: np.ndarray | None = None

    def render(self, scale: float, sigma_px: float) -> np.ndarray:
        return event_image(self.x, self.y, self.p, self.width, self.height, sigma_px, self.idx, self.H, scale)


def reference_time_us(t: np.ndarray, fraction: float = 1.0) -> int:
    """The time the events of a window are warped to: ``fraction`` of the way from its first to its last event, us."""
    t0, t1 = int(t[0]), int(t[-1])
    return t1 if fraction >= 1.0 else t0 + int(round(fraction * (t1 - t0)))


def _slices(t: np.ndarray, n_slices: int, fraction: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Slice index per event and each slice's time before the reference time (``reference_time_us``), seconds.

    Slices after the reference time get negative times: their events are moved back by the inverse motion.
    """
    t0, t1 = int(t[0]), int(t[-1])
    span = max(t1 - t0, 1)
    idx = np.minimum(((t - t0) * n_slices) // span, n_slices - 1).astype(np.int64)
    centres = t0 + (np.arange(n_slices) + 0.5) * span / n_slices
    return idx, (reference_time_us(t, fraction) - centres) / 1e6


def fit_sim2(ref: np.ndarray, cur: np.ndarray, seed: int = 0) -> np.ndarray | None:
    """Similarity (3x3) mapping ``ref`` onto ``cur`` by RANSAC (OpenCV ``estimateAffinePartial2D``); None if it fails."""
    if len(ref) < 3:
        return None
    cv2.setRNGSeed(seed)
    A, inl = cv2.estimateAffinePartial2D(np.asarray(ref, np.float32), np.asarray(cur, np.float32), method=cv2.RANSAC, ransacReprojThreshold=1.5)
    if A is None:
        return None
    return np.vstack([A, [0.0, 0.0, 1.0]])


def sim2_homographies(M: np.ndarray, seconds: float, dts: np.ndarray) -> np.ndarray:
    """Per-slice warps ``Exp(Log(M) dt / seconds)`` of a similarity ``M`` (3x3), in closed form.

    Writing the similarity as ``x -> e^z x + t`` in complex numbers (``e^z = s e^{i theta}``),
    its fractional power ``alpha`` is ``x -> e^{alpha z} x + t (e^{alpha z} - 1) / (e^z - 1)``.
    """
    ez = complex(M[0, 0], M[1, 0])
    if abs(ez) < 1e-9:
        return np.repeat(np.eye(3)[None], len(dts), axis=0)
    z = np.log(ez)
    t = complex(M[0, 2], M[1, 2])
    alpha = np.asarray(dts, np.float64) / max(seconds, 1e-9)
    eaz = np.exp(alpha * z)
    denom = ez - 1.0
    # (e^{az} - 1) / (e^z - 1) -> alpha as the motion vanishes.
    ratio = np.where(abs(denom) > 1e-12, (eaz - 1.0) / (denom if abs(denom) > 1e-12 else 1.0), alpha)
    ta = t * ratio
    out = np.zeros((len(alpha), 3, 3))
    out[:, 0, 0] = eaz.real
    out[:, 0, 1] = -eaz.imag
    out[:, 1, 0] = eaz.imag
    out[:, 1, 1] = eaz.real
    out[:, 0, 2] = ta.real
    out[:, 1, 2] = ta.imag
    out[:, 2, 2] = 1.0
    return out


def se3_homographies(K: np.ndarray, omega: np.ndarray, velocity: np.ndarray, depth: float, dts: np.ndarray) -> np.ndarray:
    """Per-slice ``K (R + t e3^T / Z) K^-1`` moving a point seen ``dt`` before the end to the end frame.

    ``omega``/``velocity`` are the camera's own-frame rates; a camera rotating by
    ``R_wc(dt) = Exp(omega dt)`` sees static points rotate by its inverse. All slices at once (session 26: one
    rotation call and stacked products instead of a loop over the slices, bit for bit the same; 0.55 -> 0.03 ms).
    """
    Ki = np.linalg.inv(K)
    dts = np.asarray(dts, np.float64)
    e3 = np.array([0.0, 0.0, 1.0])
    inv_depth = 1.0 / max(depth, 1e-6)
    R = rotvec_matrices(np.asarray(omega)[None, :] * dts[:, None]).transpose(0, 2, 1)
    t = np.matmul(-R, (np.asarray(velocity)[None, :] * dts[:, None])[:, :, None])[:, :, 0]
    return K @ (R + (t[:, :, None] * e3[None, None, :]) * inv_depth) @ Ki


@nb.njit(cache=True, error_model="numpy")
def _depth_errors(a, b, cur, ws):
    """For each inverse depth ``w`` of ``ws``: the median over the tracks of ``|(a + w b)_xy / (a + w b)_z - cur|``,
    numpy's arithmetic (``np.median(np.linalg.norm(uv - cur, axis=1))``); inf where that is not finite."""
    n = a.shape[0]
    out = np.empty(ws.shape[0])
    e = np.empty(n)
    for k in range(ws.shape[0]):
        w = ws[k]
        nan = False
        for i in range(n):
            qz = a[i, 2] + w * b[2]
            dx = (a[i, 0] + w * b[0]) / qz - cur[i, 0]
            dy = (a[i, 1] + w * b[1]) / qz - cur[i, 1]
            e[i] = np.sqrt(dx * dx + dy * dy)
            nan |= np.isnan(e[i])
        if nan:  # numpy's median is NaN then
            out[k] = np.inf
            continue
        for i in range(1, n):  # insertion sort: a few dozen tracks
            v = e[i]
            j = i - 1
            while j >= 0 and e[j] > v:
                e[j + 1] = e[j]
                j -= 1
            e[j + 1] = v
        m = n // 2
        med = e[m] if n % 2 else (e[m - 1] + e[m]) / 2.0
        out[k] = med if np.isfinite(med) else np.inf
    return out


_DEPTH_GRID = np.geomspace(1e-3, 1e3, 241)
"""The inverse depths :func:`fit_average_depth` tries first."""


def fit_average_depth(K: np.ndarray, omega: np.ndarray, velocity: np.ndarray, ref: np.ndarray, cur: np.ndarray, seconds: float) -> float | None:
    """Eq. (5) for one unknown: the depth whose SE(3) warp best maps ``ref`` tracks onto ``cur``.

    With a fronto-parallel plane the warped point is ``(a + w b) / (a_z + w b_z)``
    with ``a = K R K^-1 x``, ``b = K t`` and ``w`` the inverse depth, so the robust
    (median) reprojection error is evaluated for a whole grid of ``w`` at once (session 26: in numba,
    :func:`_depth_errors`, bit for bit numpy's; 0.7 -> 0.3 ms).
    """
    if len(ref) < 3 or np.linalg.norm(velocity) < 1e-12 or seconds <= 0:
        return None
    Ki = np.linalg.inv(K)
    R = rotvec_matrices(np.asarray(omega) * seconds)[0].T
    t = -R @ (np.asarray(velocity) * seconds)
    a = np.ascontiguousarray(np.c_[ref, np.ones(len(ref))] @ (K @ R @ Ki).T, np.float64)
    b = np.ascontiguousarray(K @ t, np.float64)
    cur = np.ascontiguousarray(cur, np.float64)
    grid = _DEPTH_GRID
    err = _depth_errors(a, b, cur, grid)
    k = int(np.argmin(err))
    if not np.isfinite(err[k]):
        return None
    fine = np.linspace(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)], 101)
    return float(1.0 / fine[int(np.argmin(_depth_errors(a, b, cur, fine)))])


class MciGenerator:
    """Renders every applicable hypothesis for a window, scores them and keeps the sharpest."""

    def __init__(self, cfg: MciConfig, image: EventImageConfig, K: np.ndarray, width: int, height: int, seed: int = 0):
        self.cfg = cfg
        self.icfg = image
        self.K = np.asarray(K, np.float64)
        self.width = int(width)
        self.height = int(height)
        self.seed = int(seed)

    def _render(self, rw: ReconstructionWindow, idx: np.ndarray | None, H: np.ndarray | None) -> tuple[np.ndarray, Splat]:
        p = rw.p if self.icfg.use_polarity else None
        sp = Splat(rw.x, rw.y, p, self.width, self.height, idx, H)
        return sp.render(1.0, self.icfg.sigma_px), sp

    def _parallax(self, rw: ReconstructionWindow, prior: MotionPrior, idx: np.ndarray, dts: np.ndarray, track_s: float,
                  sim2: np.ndarray | None) -> tuple[np.ndarray, Splat] | None:
        """H5's image, or None without enough map points or tracks (``MciConfig.parallax_min_points``)."""
        c = self.cfg
        if not c.use_parallax or prior.point_uv is None or len(prior.point_uv) < c.parallax_min_points or track_s <= 0:
            return None
        ref = np.asarray(rw.ref_pts, np.float64)
        field = depth_field(prior.point_uv, prior.point_depth, self.width, self.height)
        if field is None or len(ref) < c.parallax_min_points:
            return None
        if c.parallax_whole_window and self._has_whole(rw):
            pts = rw.whole_pts
            own = None
            if c.parallax_joint_tracks and track_s > 0:
                own = (np.stack([ref, rw.cur_pts]), np.array([rw.t_ref_us, rw.t_cur_us]), sample_depth(field, ref[:, 0], ref[:, 1]))
            fit = fit_twist_rate(self.K, pts, rw.whole_t_us, sample_depth(field, pts[0, :, 0], pts[0, :, 1]), extra=own)
            if fit is None:
                return None
            return self._parallax_image(rw, field, idx, dts, fit[0])
        cur = np.asarray(rw.cur_pts, np.float64)
        guess = None
        if c.parallax_prior_weight > 0 and prior.omega is not None and prior.velocity is not None:
            guess = np.r_[prior.omega, prior.velocity] * track_s  # the last poses' twist over the tracks' span
        fit = fit_twist(self.K, ref, cur, sample_depth(field, ref[:, 0], ref[:, 1]), prior=guess, prior_weight=c.parallax_prior_weight)
        if fit is None:
            return None
        xi, residual = fit
        if c.parallax_max_residual_ratio > 0 and sim2 is not None:
            # The depths must explain the tracks better than the similarity does, or they are not the scene's.
            moved = np.c_[ref, np.ones(len(ref))] @ sim2[:2].T
            if residual >= c.parallax_max_residual_ratio * float(np.median(np.linalg.norm(moved - cur, axis=1))):
                return None
        return self._parallax_image(rw, field, idx, dts, xi / track_s)

    def _parallax_image(self, rw: ReconstructionWindow, field: np.ndarray, idx: np.ndarray, dts: np.ndarray,
                        rate: np.ndarray) -> tuple[np.ndarray, Splat]:
        # A constant twist: points seen dts before the reference time move by Exp(omega dts)^T (X - v dts).
        u, v = warp_events(self.K, rw.x, rw.y, sample_depth(field, rw.x, rw.y), idx, np.outer(dts, rate[:3]), np.outer(dts, rate[3:]))
        p = rw.p if self.icfg.use_polarity else None
        sp = Splat(u, v, p, self.width, self.height)
        return sp.render(1.0, self.icfg.sigma_px), sp

    def _has_whole(self, rw: ReconstructionWindow) -> bool:
        """The window carries enough tracks from its start (``MciConfig.whole_window_min_tracks``)."""
        return rw.whole_pts.shape[1] >= self.cfg.whole_window_min_tracks and whole_span_s(rw.whole_t_us) > 0

    def generate(self, rw: ReconstructionWindow, prior: MotionPrior | None = None, mapped: bool = True) -> MciResult:
        """The sharpest hypothesis's MCI of ``rw``; ``mapped``: a map is tracked (``MciConfig.unwarped_own_events_before_map``)."""
        prior = prior or MotionPrior()
        cands: dict[Hypothesis, tuple[np.ndarray, Splat]] = {}
        frac = self.cfg.reference_fraction
        idx, dts = _slices(rw.t, self.cfg.time_slices, frac)
        track_s = (rw.t_cur_us - rw.t_ref_us) / 1e6
        sim2 = None
        depth = None
        # Warps map a point seen dt before the end to the end: the tracks go forward in time, so
        # a warp over dt is the tracked motion raised to dt / track_s.
        if self.cfg.use_feature_fit and self.cfg.sim2_whole_window and self._has_whole(rw):
            sim2 = fit_sim2(rw.whole_pts[0], rw.whole_pts[-1], self.seed)
            if sim2 is not None:
                cands[Hypothesis.H2_SIM2] = self._render(rw, idx, sim2_homographies(sim2, whole_span_s(rw.whole_t_us), dts))
        elif self.cfg.use_feature_fit and track_s > 0 and len(rw.ref_pts) >= 3:
            sim2 = fit_sim2(rw.ref_pts, rw.cur_pts, self.seed)
            if sim2 is not None:
                H = sim2_homographies(sim2, track_s, dts)
                cands[Hypothesis.H2_SIM2] = self._render(rw, idx, H)
        have_motion = prior.omega is not None or prior.velocity is not None
        omega = np.zeros(3) if prior.omega is None else np.asarray(prior.omega, np.float64)
        vel = np.zeros(3) if prior.velocity is None else np.asarray(prior.velocity, np.float64)
        if self.cfg.use_map_depth and have_motion and prior.map_depth is not None and prior.map_depth > 0:
            H = se3_homographies(self.K, omega, vel, prior.map_depth, dts)
            cands[Hypothesis.H1_MAP_DEPTH] = self._render(rw, idx, H)
        if self.cfg.use_pose_prior and have_motion:
            depth = fit_average_depth(self.K, omega, vel, rw.ref_pts, rw.cur_pts, track_s) if track_s > 0 else None
            z = depth if depth is not None else (prior.map_depth or 1.0)
            H = se3_homographies(self.K, omega, vel, z, dts)
            cands[Hypothesis.H3_POSE_PRIOR] = self._render(rw, idx, H)
        h5 = self._parallax(rw, prior, idx, dts, track_s, sim2)
        if h5 is not None:
            cands[Hypothesis.H5_PARALLAX] = h5
        t_ref = reference_time_us(rw.t, frac) if len(rw.t) else rw.t_end_us
        t_by = {}
        own = self.cfg.unwarped_own_events or (self.cfg.unwarped_own_events_before_map and not mapped)
        k = rw.n_overlap if own else 0
        if 0 < k < len(rw.t):
            # MciConfig.unwarped_own_events: the events this window shares with the previous one would sit unmoved in
            # both plain histograms and hold KLT at zero flow.
            p = rw.p[k:] if self.icfg.use_polarity else None
            sp = Splat(rw.x[k:], rw.y[k:], p, self.width, self.height)
            cands[Hypothesis.H4_NONE] = (sp.render(1.0, self.icfg.sigma_px), sp)
            t_by[Hypothesis.H4_NONE.value] = reference_time_us(rw.t[k:], frac)
        else:
            cands[Hypothesis.H4_NONE] = self._render(rw, None, None)
        scores = {h.value: local_std_score(img, self.cfg.patch_px) for h, (img, _) in cands.items()}
        # Highest score wins; ties go to the earlier hypothesis in H1..H5 order (deterministic).
        best = max(sorted(cands, key=lambda h: h.value), key=lambda h: scores[h.value])
        img = cands[best][0]
        return MciResult(t_us=t_by.get(best.value, t_ref), image=img, image8=to_uint8(img), hypothesis=best, scores=scores, n_events=len(rw.t), sim2=sim2, depth=depth,
                         candidates={h.value: im for h, (im, _) in cands.items()}, splats={h.value: sp for h, (_, sp) in cands.items()},
                         t_by_hypothesis={**t_by, "window": t_ref} if t_by else {})
