"""Line landmarks for event-only maps: straight MCI edges tracked, triangulated as 3-D lines and used to place the
camera where the point tracks starve.

Indoors the camera yaws past the room's vertical edges, and while it does the MCIs show little else: one to four long,
straight, motion-compensated lines (session 20, seed 0: a median 4 line segments over 20 px in a coasted MCI, all
within 30 deg of vertical), on which KLT slides and few map points lie (:mod:`evpose.slam.edge_tracking`). Here those
edges become landmarks:

- detection: OpenCV's line segment detector on the blurred MCI; a thin ridge of events gives one segment per flank,
  with opposite gradient directions, and the two are merged into the ridge's centre line;
- association: each line track's newest segment is predicted into the next MCI (its 3-D line projected by the pose,
  or, before it has one, carried by the rotation between the two poses) and matched to the nearest detected segment of
  similar direction that overlaps it;
- triangulation: each observation at a placed MCI back-projects its segment to a plane through the camera centre; the
  3-D line is the least-squares intersection of the track's planes (SVD), once two of them differ by at least
  ``min_parallax_deg`` (the across-edge parallax of the camera's translation);
- tracking: when the map is starved, its 3-D lines are projected at the coasted pose, matched to the MCI's segments,
  and each matched line gives two 1-D residuals, the distances of its projected end points from the detected line
  (free along the line), solved with the coast as a Gaussian prior by :func:`evpose.slam.edge_tracking.solve_pose_across_edges`.

Measured (session 20, ``/tmp/s20/lines9b``: ``exp.py`` is the lead's harness, ``diag.py`` / ``dbg*.py`` / ``chk*.py``
log each attempt against the truth). Indoor, event-only, seeds 0-7, defaults: ATE 6.83 %, from the events 40.7 %, 30
maps, CPU per MCI median 15.1 ms.

- Diagnosis. 61 coasted stretches over the 8 runs, median 61 ms, 75th percentile 394 ms, longest 627 ms; 90 % of the
  coasted time lies in stretches over 100 ms. Every one of the 22 map ends is a starved map (0-5 tracked map points) at
  the end of a coast or after a blank wall. The coasted MCIs do show straight edges (seed 0: a median 4 segments over
  20 px, all near vertical; tracked MCIs 12); a line track follows them through a coast for 20-30 MCIs.
- Why the lines do not carry the pose: they are rarely triangulated. The edges seen while coasting are met during the
  coast, and over a track's life the camera's translation gives under about 1 deg of across-edge parallax for a far
  vertical edge (seed 0, a 110 px edge tracked over 16 MCIs: triangulation angle 0.05-1.2 deg, depth of either sign),
  while the poses it is observed from disagree with its image motion by 4-5 px (about 1 deg). The PnP poses are no
  steadier: between PnP-placed MCIs 40-60 ms apart (seeds 0, 3, 4) the relative rotation is off the truth by a median
  1.86 deg for a true 3.00 deg (estimated 4.18; 5-25 ms apart: 0.71 for 0.82; landing seeds 0-1, 40-60 ms: 0.97 for
  1.35). Over seeds 0-7 (315 pairs 40-60 ms apart, true rotation over 1 deg) the estimated rotation about the true
  axis is a median 1.26 times the true one (quartiles 0.87-1.49; 7 of 8 seeds over 1, seed 2 0.79), its error a median
  0.61 of the true rotation; landing seeds 0-3 (159 pairs) 0.97 (0.65-1.29), error 0.67. Of 369 line-tracking attempts (seeds 0, 3, 5; ``update_from_coast``, ``match_px`` 12, ``ambiguity_ratio``
  0.8), 242 found fewer than ``min_lines`` 3-D lines in the map, 21 matched too few, 4 were rejected by the solver, 32
  came after ``max_span_s``, and 70 were placed.
- Where 3-D lines are matched, the solved pose stays at the coast: rotation relative to the last PnP pose against the
  truth (seeds 0-7, ``update_from_coast``, ``shift_search_px`` 30, 139 line-tracked MCIs) median coast / solved 1.86 /
  1.93 deg within 50 ms of the last PnP pose, 9.68 / 9.64 within 50-150 ms, 16.0 / 15.6 within 150-400 ms, mostly yaw;
  with ``EdgeTrackingConfig.sigma_rotation_deg`` 5 the same (seed 3). The lines agree with the map they were
  triangulated in, and so with its coast.
- Indoor seeds 0-7 (ATE % / from the events % / maps, line-tracked MCIs of about 1500): on with the defaults 7.38 /
  41.5 / 31, 29; ``shift_search_px`` 30 7.56 / 42.3 / 31, 35; ``update_from_coast`` 8.50 / 42.6 / 28, 125; with
  ``shift_search_px`` 30 8.42 / 44.0 / 28, 139; with ``match_px`` 12 and ``ambiguity_ratio`` 0.8 instead 7.24 / 45.9 /
  28, 119 (held-out seeds 8-11: 7.98 -> 7.75 %, from the events 44.3 -> 48.6 %); ``refine_pnp`` 7.02 / 41.2 / 31.
  Per seed the ATE moves by up to 10 points either way (seed 4 7.37 -> 13.30 % with 10 line-tracked MCIs): a handful
  of line-tracked MCIs redraws which MCIs re-localise afterwards. CPU per MCI median 16.2-19.4 ms (single runs, not
  paired).

Off by default: no variant lowers the ATE. What limits the lines is the precision of the poses they are triangulated
from, not their detection.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from evpose.core.trajectory import invert_pose


@dataclass
class LineLandmarkConfig:
    """Line landmarks of event-only maps (:mod:`evpose.slam.line_landmarks`)."""

    enabled: bool = False
    """Track straight MCI edges as 3-D lines, and place a starved event-only map's MCI on them before coasting. Off:
    indoor seeds 0-7 ATE 6.83 -> 7.38 % (module docstring)."""
    min_length_px: float = field(default=25.0, metadata={"min": 5.0, "max": 300.0, "step": 1.0, "unit": "px"})
    """Shortest detected segment used, pixels."""
    blur_sigma_px: float = field(default=1.5, metadata={"min": 0.0, "max": 5.0, "step": 0.1, "unit": "px"})
    """Gaussian blur of the 8-bit MCI before the segment detector, pixels."""
    merge_px: float = field(default=8.0, metadata={"min": 0.5, "max": 10.0, "step": 0.5, "unit": "px"})
    """Two flanks of one event ridge (opposite gradients, parallel) closer than this are merged, pixels."""
    match_px: float = field(default=8.0, metadata={"min": 1.0, "max": 50.0, "step": 0.5, "unit": "px"})
    """A detected segment matches a predicted line when its mid point lies this close to it, pixels."""
    match_angle_deg: float = field(default=6.0, metadata={"min": 0.5, "max": 30.0, "step": 0.5, "unit": "deg"})
    """... and its direction differs by less than this, degrees."""
    ambiguity_ratio: float = field(default=0.6, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """A match is dropped when the second-nearest candidate is within the gate and the nearest is not closer than this
    share of its distance, ratio."""
    min_parallax_deg: float = field(default=1.0, metadata={"min": 0.05, "max": 20.0, "step": 0.05, "unit": "deg"})
    """Least triangulation angle of a 3-D line: the widest angle, seen from the line, between two of its observations'
    camera centres (across the line), degrees."""
    max_residual_px: float = field(default=2.0, metadata={"min": 0.1, "max": 10.0, "step": 0.1, "unit": "px"})
    """A triangulated line whose end points lie farther than this from any of its observed lines is not used, pixels."""
    max_tracks: int = field(default=40, metadata={"min": 1, "max": 500, "step": 1, "unit": "lines"})
    """Most line tracks kept, lines."""
    max_misses: int = field(default=2, metadata={"min": 0, "max": 50, "step": 1, "unit": "MCIs"})
    """A track not matched in this many consecutive placed MCIs is dropped, MCIs."""
    max_observations: int = field(default=30, metadata={"min": 2, "max": 500, "step": 1, "unit": "MCIs"})
    """Newest observations (planes) kept per track for its triangulation, MCIs."""
    min_lines: int = field(default=2, metadata={"min": 1, "max": 50, "step": 1, "unit": "lines"})
    """Fewest 3-D lines agreeing with the solved pose for a starved MCI to be placed on them (1, with
    ``update_from_coast``, ``match_px`` 12 and ``ambiguity_ratio`` 0.8: indoor seeds 0-7 7.24 -> 7.76 %, from the events
    45.9 -> 49.0 %), lines."""
    max_span_s: float = field(default=0.4, metadata={"min": 0.0, "max": 5.0, "step": 0.05, "unit": "s"})
    """Longest stretch of line-tracked MCIs since the last MCI placed by PnP on point tracks, seconds."""
    shift_search_px: float = field(default=0.0, metadata={"min": 0.0, "max": 100.0, "step": 1.0, "unit": "px"})
    """Before matching the 3-D lines of a starved MCI, the image shift (up to this far) that brings most of their
    predicted segments onto detected ones is applied to all of them (a coasted yaw error moves every line alike);
    0: off (30: indoor seeds 0-7 7.38 -> 7.56 %), pixels."""
    refine_pnp: bool = False
    """A PnP-placed MCI's pose is re-solved with its inlier points and the matched 3-D lines together (1-D residuals,
    Huber ``EdgeTrackingConfig.huber_px``), the PnP pose as a loose prior (on: indoor seeds 0-7 7.38 -> 7.02 %, against
    6.83 % with lines off)."""
    refine_sigma_rotation_deg: float = field(default=5.0, metadata={"min": 0.01, "max": 90.0, "step": 0.1, "unit": "deg"})
    """Sigma of that prior's rotation about each camera axis, degrees."""
    refine_sigma_translation_ratio: float = field(default=0.05, metadata={"min": 0.0001, "max": 1.0, "step": 0.001, "unit": "ratio"})
    """Sigma of that prior's translation along each camera axis, as a share of the median depth of the points, ratio."""
    update_from_coast: bool = False
    """Coasted MCIs add observations and new tracks too, at the coasted pose (off: only placed MCIs do; on: indoor seeds
    0-7 7.38 -> 8.50 %, line-tracked MCIs 29 -> 125)."""
    update_from_lines: bool = True
    """Line-tracked MCIs add observations and new tracks too (off: only PnP-placed MCIs do, so the lines in use were
    all born before the starved stretch)."""


@dataclass
class LineTrack:
    id: int
    seg: np.ndarray
    """Newest matched segment (x0, y0, x1, y1), ideal-pinhole pixels."""
    T_cw: np.ndarray
    """Pose ``T_cam_world`` at the newest observation (4, 4)."""
    planes: list = field(default_factory=list)
    """Back-projected planes (4,) ``n . X + d = 0`` of the observations, world frame, unit normals."""
    centres: list = field(default_factory=list)
    """Camera centres (3,) of the observations, world frame."""
    X: np.ndarray | None = None
    """End points of the 3-D line (2, 3), world frame; None until triangulated."""
    misses: int = 0


@dataclass
class LineMap:
    """Line tracks of one map (reset when the active map changes or is re-initialised)."""

    map_id: int = -1
    restructured: int = 0
    tracks: list[LineTrack] = field(default_factory=list)
    next_id: int = 0

    def landmarks(self) -> list[LineTrack]:
        return [t for t in self.tracks if t.X is not None]


def _normalise(segs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segments oriented with y0 <= y1 (ties x0 <= x1), and a flag for those flipped (the gradient side changes)."""
    flip = (segs[:, 3] < segs[:, 1]) | ((segs[:, 3] == segs[:, 1]) & (segs[:, 2] < segs[:, 0]))
    out = segs.copy()
    out[flip] = segs[flip][:, [2, 3, 0, 1]]
    return out, flip


def detect_segments(img8: np.ndarray, cfg: LineLandmarkConfig) -> np.ndarray:
    """Straight edges of an MCI as segments (N, 4) (x0, y0, x1, y1), the two flanks of a ridge merged."""
    im = cv2.GaussianBlur(img8, (0, 0), cfg.blur_sigma_px) if cfg.blur_sigma_px > 0 else img8
    found = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD).detect(im)[0]
    if found is None:
        return np.zeros((0, 4))
    segs = found.reshape(-1, 4).astype(np.float64)
    segs = segs[np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]) >= cfg.min_length_px]
    segs, flip = _normalise(segs)
    used = np.zeros(len(segs), bool)
    out = []
    for i in np.argsort(-np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]), kind="stable"):
        if used[i]:
            continue
        used[i] = True
        best, best_d = -1, cfg.merge_px
        for j in np.flatnonzero(~used & (flip != flip[i])):
            d, ang, ovl = _relation(segs[i], segs[j])
            if ang < 5.0 and ovl > 0 and d < best_d:
                best, best_d = j, d
        if best < 0:
            out.append(segs[i])
            continue
        used[best] = True
        a, b = segs[i], segs[best]
        # The ridge's centre line: the longer flank moved half-way towards the other one.
        n = _normal(a)
        shift = 0.5 * float(n @ (0.5 * (b[:2] + b[2:]) - a[:2]))
        out.append(a + np.r_[n, n] * shift)
    return np.array(out).reshape(-1, 4)


def _normal(seg: np.ndarray) -> np.ndarray:
    d = seg[2:] - seg[:2]
    d = d / max(float(np.linalg.norm(d)), 1e-12)
    return np.array([-d[1], d[0]])


def _relation(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """(distance of ``b``'s mid point from ``a``'s line (px), angle between them (deg), overlap of ``b``'s projection
    onto ``a`` with ``a``'s extent (px; negative: the gap))."""
    da = a[2:] - a[:2]
    la = max(float(np.linalg.norm(da)), 1e-12)
    ua = da / la
    db = b[2:] - b[:2]
    ub = db / max(float(np.linalg.norm(db)), 1e-12)
    n = np.array([-ua[1], ua[0]])
    mid = 0.5 * (b[:2] + b[2:])
    dist = abs(float(n @ (mid - a[:2])))
    ang = float(np.degrees(np.arccos(min(abs(float(ua @ ub)), 1.0))))
    s0, s1 = sorted((float(ua @ (b[:2] - a[:2])), float(ua @ (b[2:] - a[:2]))))
    return dist, ang, min(s1, la) - max(s0, 0.0)


def match_segments(pred: list[np.ndarray], segs: np.ndarray, cfg: LineLandmarkConfig, min_overlap_px: float = -10.0) -> list[int]:
    """For each predicted segment the index of its detected segment (-1: none), one detection per prediction at most."""
    cand = []
    for i, p in enumerate(pred):
        scored = []
        for j, s in enumerate(segs):
            d, ang, ovl = _relation(p, s)
            if d < cfg.match_px and ang < cfg.match_angle_deg and ovl > min_overlap_px:
                scored.append((d, j))
        scored.sort()
        if not scored or (len(scored) > 1 and scored[0][0] > cfg.ambiguity_ratio * scored[1][0]):
            continue
        cand.append((scored[0][0], i, scored[0][1]))
    out = [-1] * len(pred)
    taken = set()
    for _, i, j in sorted(cand):
        if j not in taken:
            out[i] = j
            taken.add(j)
    return out


def common_shift(pred: list[np.ndarray], segs: np.ndarray, cfg: LineLandmarkConfig) -> np.ndarray:
    """The image shift (2,) within ``shift_search_px`` that puts the most predicted segments within ``match_px / 2`` of
    a detected one of similar direction (ties: the smallest shift); zero when no shift brings two of them onto lines."""
    cands = [np.zeros(2)]
    for p in pred:
        n = _normal(p)
        for s in segs:
            d, ang, _ = _relation(p, s)
            if ang < cfg.match_angle_deg:
                off = float(n @ (0.5 * (s[:2] + s[2:]) - p[:2]))
                if abs(off) <= cfg.shift_search_px:
                    cands.append(off * n)
    best, best_key = np.zeros(2), (0, 0.0)
    for c in cands:
        moved = [p + np.r_[c, c] for p in pred]
        hits = sum(any(_relation(q, s)[0] < 0.5 * cfg.match_px and _relation(q, s)[1] < cfg.match_angle_deg for s in segs) for q in moved)
        key = (hits, -float(np.linalg.norm(c)))
        if key > best_key:
            best, best_key = c, key
    return best if best_key[0] >= 2 else np.zeros(2)


def backproject_plane(K: np.ndarray, T_wc: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """The plane (n, d) (4,), unit ``n``, world frame, through the camera centre and the segment's pixels."""
    Kinv = np.linalg.inv(K)
    r0 = Kinv @ np.r_[seg[:2], 1.0]
    r1 = Kinv @ np.r_[seg[2:], 1.0]
    n = T_wc[:3, :3] @ np.cross(r0, r1)
    n /= max(float(np.linalg.norm(n)), 1e-12)
    return np.r_[n, -float(n @ T_wc[:3, 3])]


def triangulate_line(planes: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Least-squares intersection of planes (N, 4): a point on the line and its unit direction."""
    _, _, Vt = np.linalg.svd(planes)
    # The two right singular vectors of the smallest singular values span the homogeneous points on all the planes.
    Y1, Y2 = Vt[2], Vt[3]
    w1, w2 = Y1[3], Y2[3]
    den = w1 * w1 + w2 * w2
    d = (w2 * Y1 - w1 * Y2)[:3]  # the combination at infinity: the direction
    nd = float(np.linalg.norm(d))
    if den < 1e-18 or nd < 1e-12:
        return None
    return (w1 * Y1 + w2 * Y2)[:3] / den, d / nd


def triangulation_angle_deg(X0: np.ndarray, d: np.ndarray, centres: np.ndarray) -> float:
    """Widest angle, seen from the line (X0, d), between the directions across it to the camera centres, degrees."""
    v = centres - X0
    v = v - np.outer(v @ d, d)
    nv = np.linalg.norm(v, axis=1, keepdims=True)
    if float(nv.min()) < 1e-9:
        return 0.0  # a camera centre on the line: the planes do not intersect in a line
    v /= nv
    return float(np.degrees(np.arccos(np.clip((v @ v.T).min(), -1.0, 1.0))))


def _landmark(K: np.ndarray, T_wc: np.ndarray, t: LineTrack, cfg: LineLandmarkConfig) -> np.ndarray | None:
    """End points (2, 3) of the track's 3-D line at its newest segment's ends; None when it is not triangulated well."""
    P = np.array(t.planes)
    line = triangulate_line(P)
    if line is None:
        return None
    X0, d = line
    C = np.array(t.centres)
    if triangulation_angle_deg(X0, d, C) < cfg.min_parallax_deg:
        return None
    P0, a0 = closest_on_line(K, T_wc, t.seg[:2], X0, d)
    P1, a1 = closest_on_line(K, T_wc, t.seg[2:], X0, d)
    if a0 <= 0 or a1 <= 0:
        return None
    X = np.stack([P0, P1])
    # Distance of each end point from each observed plane, in pixels at its distance from that camera.
    dist = np.abs(X @ P[:, :3].T + P[:, 3]) / np.linalg.norm(X[:, None, :] - C[None], axis=2)
    if float(dist.max()) * K[0, 0] > cfg.max_residual_px:
        return None
    return X


def closest_on_line(K: np.ndarray, T_wc: np.ndarray, uv: np.ndarray, X0: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, float]:
    """Point of the line (X0, d) nearest the ray through pixel ``uv`` and its depth along that ray."""
    C = T_wc[:3, 3]
    r = T_wc[:3, :3] @ (np.linalg.inv(K) @ np.r_[uv, 1.0])
    # Minimise |C + a r - X0 - s d| over a, s.
    M = np.array([[r @ r, -(r @ d)], [r @ d, -(d @ d)]])
    rhs = np.array([r @ (X0 - C), d @ (X0 - C)])
    try:
        a, s = np.linalg.solve(M, rhs)
    except np.linalg.LinAlgError:
        return X0, -1.0
    return X0 + s * d, float(a)


def project_segment(K: np.ndarray, T_cw: np.ndarray, X: np.ndarray) -> np.ndarray | None:
    """Pixels (4,) of the 3-D segment ``X`` (2, 3); None when an end point lies behind the camera."""
    Xc = X @ T_cw[:3, :3].T + T_cw[:3, 3]
    if (Xc[:, 2] <= 1e-6).any():
        return None
    uv = Xc[:, :2] / Xc[:, 2:] * np.array([K[0, 0], K[1, 1]]) + np.array([K[0, 2], K[1, 2]])
    return uv.ravel()


def _rotated(K: np.ndarray, T_cw_new: np.ndarray, T_cw_old: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """``seg`` carried by the rotation between two poses (points at infinity)."""
    H = K @ T_cw_new[:3, :3] @ T_cw_old[:3, :3].T @ np.linalg.inv(K)
    p = (H @ np.c_[seg.reshape(2, 2), np.ones(2)].T).T
    return (p[:, :2] / p[:, 2:]).ravel()


def _in_image(seg: np.ndarray, w: int, h: int, margin: float = 0.0) -> bool:
    xs, ys = seg[[0, 2]], seg[[1, 3]]
    return bool((xs.max() >= -margin) and (xs.min() < w + margin) and (ys.max() >= -margin) and (ys.min() < h + margin))


def predict(lm: LineMap, K: np.ndarray, T_cw: np.ndarray, w: int, h: int, landmarks_only: bool) -> tuple[list[LineTrack], list[np.ndarray]]:
    """The tracks expected in view at ``T_cw`` and their predicted segments."""
    tracks, pred = [], []
    for t in lm.tracks:
        if t.X is not None:
            p = project_segment(K, T_cw, t.X)
        elif landmarks_only:
            continue
        else:
            p = _rotated(K, T_cw, t.T_cw, t.seg)
        if p is not None and np.isfinite(p).all() and _in_image(p, w, h):
            tracks.append(t)
            pred.append(p)
    return tracks, pred


def update_tracks(lm: LineMap, K: np.ndarray, T_wc: np.ndarray, segs: np.ndarray, size: tuple[int, int], cfg: LineLandmarkConfig) -> int:
    """Add the segments ``segs`` of an MCI placed at ``T_wc`` to the tracks: match, extend, triangulate, start new
    tracks, drop stale ones. Returns how many tracks were matched."""
    h, w = size
    T_cw = invert_pose(T_wc)
    tracks, pred = predict(lm, K, T_cw, w, h, landmarks_only=False)
    match = match_segments(pred, segs, cfg) if len(segs) else [-1] * len(tracks)
    seen = set()
    for t, j in zip(tracks, match):
        if j < 0:
            continue
        seen.add(t.id)
        t.seg, t.T_cw, t.misses = segs[j].copy(), T_cw, 0
        t.planes = (t.planes + [backproject_plane(K, T_wc, segs[j])])[-cfg.max_observations:]
        t.centres = (t.centres + [T_wc[:3, 3].copy()])[-cfg.max_observations:]
        t.X = _landmark(K, T_wc, t, cfg) if len(t.planes) >= 2 else None
    for t in lm.tracks:
        if t.id not in seen:
            t.misses += 1
    lm.tracks = [t for t in lm.tracks if t.misses <= cfg.max_misses]
    used = {j for j in match if j >= 0}
    for j in range(len(segs)):
        if j in used or len(lm.tracks) >= cfg.max_tracks:
            continue
        lm.tracks.append(LineTrack(lm.next_id, segs[j].copy(), T_cw, [backproject_plane(K, T_wc, segs[j])], [T_wc[:3, 3].copy()]))
        lm.next_id += 1
    return len(seen)


def line_measurements(lm: LineMap, K: np.ndarray, T_cw: np.ndarray, segs: np.ndarray, size: tuple[int, int],
                      cfg: LineLandmarkConfig) -> tuple[list[LineTrack], np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """The landmarks matched in an MCI predicted at ``T_cw``, as the 1-D solver takes them: (tracks, end points (2M, 3),
    a pixel of the detected line for each (2M, 2), its normal (2M, 2), the detected segment's index per track)."""
    h, w = size
    tracks, pred = predict(lm, K, T_cw, w, h, landmarks_only=True)
    if cfg.shift_search_px > 0 and len(segs) and tracks:
        c = common_shift(pred, segs, cfg)
        pred = [p + np.r_[c, c] for p in pred]
    match = match_segments(pred, segs, cfg) if len(segs) and tracks else []
    used, Xw, uv, nrm, idx = [], [], [], [], []
    for t, j in zip(tracks, match):
        if j < 0:
            continue
        s = segs[j]
        used.append(t)
        idx.append(j)
        Xw.extend(t.X)
        uv.extend([0.5 * (s[:2] + s[2:])] * 2)
        nrm.extend([_normal(s)] * 2)
    if not used:
        return [], np.zeros((0, 3)), np.zeros((0, 2)), np.zeros((0, 2)), []
    return used, np.array(Xw), np.array(uv), np.array(nrm), idx
