"""Event window selection (paper Algorithm 1): tiny windows, tiny frames, KLT tracks, MCI trigger and ``N_e`` adaptation.

Events arrive already undistorted (float ideal-pinhole pixels). Tiny windows of
``N_e`` events are tested against the event-generation rate ``th_e`` (eq. 6),
splatted into tiny frames, and FAST features of the first frame are tracked by
KLT through the following ones. When the median feature displacement (eq. 7)
exceeds ``th_fd`` the collected events form a reconstruction window for an
MCI, and ``N_e`` becomes ``floor(N_f N_e / N_x)`` (eq. 8).

Session 26 (``/tmp/s26/window26``), CPU, outputs bit for bit those of main (``ident.py`` / ``ident2.py``, copies of
``/tmp/s26/speed26``'s: trajectories and every step's tracks, hypothesis, scores, MCI and pose of landing event-only
seeds 0-11, event-inertial 0 and 2 and E-I-C2 1; indoor event-only 0-3 and E-I-C2 1). On landing seed 0 the selection
(:meth:`EventWindowSelector.push`) took 11.8 ms of main-thread CPU per MCI (``wsplit.py``, thread_time per function):
KLT 8.3 (399 ``track_features`` calls: 162 for the window's own features, 237 for the carried ones), FAST and
Shi-Tomasi 0.9, the two-view RANSAC 0.6, 8-bit scaling 0.5, splats 0.5, dispatch 0.5, ``np.mean`` of the tiny
frames' times 0.2. Kept: the carried features move between the same two tiny frames as the window's own, so both go
through one KLT call (``features.track_feature_sets``; OpenCV tracks each point on its own, and the two image pyramids
with their derivatives, 0.27 ms a call, are built once instead of twice); the tiny frame's mean time from an integer
sum (:func:`mean_time_us`); the per-cell rank of ``detect_features`` without a loop (``features.rank_in_runs``).
Alternating processes (``wloop.sh`` / ``wbench.py``, 4 runs each, median, loaded machine), selection per MCI main ->
branch: landing seeds 0-3 11.96 / 12.05 / 12.57 / 12.20 -> 11.47 / 11.43 / 12.07 / 11.16 ms, indoor 0-1 8.55 / 8.67
-> 8.22 / 7.91 ms; the whole main thread per MCI (``run_slam``'s thread CPU over the MCIs) -0.05 to -2.5 ms. What is
left is OpenCV's KLT itself (about 7 ms per landing MCI, 30 us per point for both passes, 23 px window, 3 levels):
its Python binding takes no prebuilt pyramids (a list of levels is refused), so each call still rebuilds both
pyramids, and cutting the per-point work bit for bit would take a numba port of OpenCV's fixed-point, SIMD-ordered
``LKTrackerInvoker``. Skipping the backward pass for points that fail the forward one would save under 1 % (147 of
17797 points, ``t_fail.py``).

Why sparser events make the event-only map worse (session 26, ``/tmp/s26/sparse26``; the lab: the simulated landing with
its events kept with probability 0.4 before 1.2 s, "dimmed", or 0.5 throughout, "thinned", ``dimx.py``; defaults:
dimmed seeds 0-7 4.38 %, thinned 4.54 %, full 1.44 % over seeds 0-23). Three separate causes, none of them the
two-view start:

- The fine-grid warm-up reads a landing with fewer events as a room and keeps the sensor grid for the whole
  recording (figures in ``FeatureConfig.klt_upsample_min_events_per_px``): the fine grid forced on, dimmed 2.46 %,
  thinned 2.84 %. The rooms run on the sensor grid by design, so this is not what is wrong indoors.
- ``N_e`` runs down to ``min_events`` (``wdiag.py``, ``diag.py``): dimmed seed 7 over 0.3-0.9 s has 36 windows per 0.3
  s with ``N_e`` 300, reference to last tiny frame 3.8-5.2 ms, and a median feature displacement ``M_fd`` of 4.5-5.7
  px, where the full recording's windows there span 24-26 ms for 5.6-6.4 px. Against the truth (``truedisp.py``: each
  reference feature ray-cast at the reference tiny frame's true pose, projected at the last one's) the windows at the
  clamp measured a median 5.8 px where the features moved 0.94 px (42 windows), the others 5.05 against 4.41 px (full
  recording: 5.18 against 4.73): the rest is KLT jitter on tiny frames of 300 events, which the displacement test
  cannot tell from motion (the tracks' median residual to a similarity fitted to them is 2.5-4.1 px there, 0.4-1.4 px
  in the landing's windows). Each 2-frame dispatch shrinks ``N_e`` by eq. (8), which makes the next frames sparser
  still; the MCIs then hold ~1600 events over ~6 ms (the full run's 20000-27000 over 34-40 ms), and the map's position
  error after a Sim(3) fit on t < 1.2 s is 33 cm RMS over 4.1 m (full: 12 cm), its rotation per step no worse (median
  0.48 against 0.69 deg). The indoor rooms do the same: 55-64 % of their MCIs (seeds 0-7, ``clamp.py``) are dispatched
  at ``N_e`` 300 with 1200-1500 events, and 20 % of those are tracked against 63 % of the rest (~4200 events), so the
  rooms' "1800 events per MCI" is mostly this clamp; and their displacement is as false: indoor seeds 0-3, 77-93
  windows each at the clamp, measured 6.2-6.3 px against a true 1.31-1.41 px (above it 5.2-5.3 against 3.8-4.5).
  Stopping the runaway (``EventWindowConfig.noise_residual_px``, or a higher ``min_events``) mends the dimmed seed 7
  (10.65 -> 1.78 %) but not the rooms (figures in those fields); the similarity residual of ``noise_residual_px``
  misses most of the rooms' false windows, though (their jitter is coherent enough: seed 0 with 2.0 px still has 64
  windows at the clamp, measured 5.9 px against a true 1.36), and a floor on ``N_e`` changes every window: a test that
  catches the rooms' false windows was not found, and session 27 (below) shows that a perfect one is worth nothing
  indoors. The first
  two causes together account for the dimmed landing: ``noise_residual_px`` 2.0 with the fine grid forced on gives
  dimmed seeds 0-7 1.68 % (8 of 8 within 2 %; the full recordings 1.36 %), against 3.04 / 2.46 % with either alone;
  thinned 2.85 % (fine grid alone 2.84: no runaway there; the full-density landing runs never reach the clamp either).
- Fewer events per MCI make each KLT step less precise (``steperr.py``: each track's step error against the true
  projection of its ray-cast at the previous MCI; landing seeds 0-3, fine grid forced on, ``min_event_rate`` 0.15):
  map-point tracks of tracked MCIs median 0.334 -> 0.425 px (90th percentile 1.55 -> 1.59), all steps 0.489 -> 0.563
  px, with MCIs of 11000 -> 5600 events (more tracks survive each step: median 0.70 -> 0.78). Thinned and so
  configured the landing is at 3.00 % (1.46-4.96) against 1.44 %, and longer windows do not win the events back
  (``feature_displacement_px``). The low rate of a thinned recording also splits its map in the slow turn
  (``min_event_rate``).

The two-view start is not it: on the thinned landing the accepted pairs (17-54 ms, parallax 0.45-2.88 deg) are
0.19-1.99 deg off in rotation and 6-36 deg in translation direction, as on the full one (seeds 0, 7: 0.22 / 1.36 deg,
18 / 85 deg), and replacing each by the true relative pose (points re-triangulated, ``diag.py`` with ``ORACLE=1``)
takes thinned seeds 0-7 from 3.00 to 3.85 %.

Session 27 (``/tmp/s27/room27``), what right windows are worth in the rooms: nothing. ``oexp.py``
(``/tmp/s25/auto9/exp.py`` plus each seed's share of MCIs at the ``min_events`` clamp and a timeline) with ``ORACLE=1``
replaces ``M_fd`` (:meth:`EventWindowSelector._median_displacement`) by the true median displacement of the same live
features (``truedisp.py``'s), all else unchanged. Indoor event-only seeds 0-7 (defaults 6.84 %, tracked min 86.2 %, from
the events 40.8 % of the time, 61 % of 175-200 MCIs at the clamp): 7.37 % (paired +0.53 +- 1.30, 5 better; tracked min
60.4 %, from the events 42.1 %, 10 % of 90-106 MCIs at the clamp); with ``th_fd`` 5 7.05 % (from the events 32.7 %); the
truth only while ``N_e`` is at the clamp (``ORACLE=clamp``: a perfect detector of the false windows, the others KLT's)
9.86 % (+3.02 +- 1.30, 2 better; still 42 % at the clamp). Held-out 8-11 (7.98 %): 7.97 / 7.08 %. Over the chaos
(``pool.py``: seeds 0-11 under the defaults and session 23's four perturbations, ``TrackingConfig.ba_huber_px`` 1.9 /
2.1, ``reprojection_threshold_px`` 2.4 / 2.6; 60 runs each): 7.87 -> 8.68 % (paired +0.81 +- 0.49, 27 better), from the
events 42.5 -> 41.1 %, tracked 93.3 -> 80.4 % (runs under 80 %: 1 -> 28). E-I-C2 indoor seeds 0-7 (metric ATE 19.60 %,
RPE at most 0.0067 m/m and 0.0047 deg/m): 18.04 % (-1.56 +- 2.06, 3 better), RPE at most 0.0173 m/m and 0.0179 deg/m,
from the events 45.1 -> 31.3 %. So no detector was built. One would be easy: the KLT displacement between the odd and
the even events of the current tiny window at the live features (``floor_diag.py``; the halves share their motion, so it
is sampling noise; medians) is 4.8-5.7 px in the rooms' clamp windows (seeds 0-3: ``M_fd`` 6.2-6.3, true 1.3-1.4),
2.4-2.6 in their others (5.2-5.3 against 3.8-4.5), 1.4-1.6 on landing seeds 0, 7 (5.1-5.2 against 4.7-4.8): ``M_fd``
over it 1.1-1.3 / 2.0-2.2 / 3.2-3.7, for 2.2-2.4 ms of main-thread CPU per tiny window (``floor_cpu.py``: two splats,
two 8-bit scalings, one KLT call at 40 points). KLT over-reads the rooms' dense start as well (seed 0's first 0.1 s:
``M_fd`` 4.1-7.6 px at dispatch for a true 1.4-3.8), and those MCIs track. What limits the rooms (``cond.py``, the 48
perturbed runs each, 144 s, by the recording's event rate; tracked from the events KLT / oracle): under 50k events/s
(sparse and blank walls) 31 % of the time, 5-7 / 4-14 %; 100-200k/s (turns, 30-110 deg/s) 24 %, 8-28 / 10-21 %;
50-100k/s 36 %, 51-90 / 57-85 %; over 200k/s (the start) 8 %, 74-80 / 47-49 % (seed 0: the oracle keeps ``N_e`` at 2000,
MCIs of 12000 events with 19-30 tracks against 150). The main failure is ``SlamFailure.STARVED`` (0.7-1.35 s of each 3 s
run; blank walls 0.5 s): in seed 0's turn (1.0-1.6 s) 94 keyframes in 96 MCIs grow the map from 124 to 538 points, yet
at most 17 tracks per MCI carry one (``TrackingConfig.min_inliers`` 12) and 1 MCI is tracked (oracle: 2 of 30, at most
14). Their tracks die between MCIs (``survive.py``, the share of the track ids of one MCI alive in the next): with a map
point 0.23-0.52 in the turn against 0.77-0.90 where it tracks, all tracks 0.34-0.50 against 0.60-0.77 (tracks without a
point die about as fast, which points at KLT's MCI-to-MCI step rather than the pose's outlier checks), 3-6 new points
per MCI; with the oracle's MCIs of 3700-5600 events no better (0.48-0.65 with a point, all 0.23-0.33, only 23-56 tracks
alive). That is for the tracker and the MCIs of a fast turn, not for the window selection.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from evpose.slam.config import EventImageConfig, EventWindowConfig, FeatureConfig
from evpose.slam.event_image import event_image, to_uint8
from evpose.slam.features import detect_features, track_feature_sets, track_features
from evpose.slam.reconstruction_window import ReconstructionWindow, WindowEvent


@dataclass
class _Chunk:
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    p: np.ndarray


@dataclass
class _Carried:
    """The previous window's features, tracked on through the next window (one position per tiny frame)."""

    t_us: list
    pts: list
    alive: np.ndarray
    last8: np.ndarray


@dataclass
class WindowState:
    """Mutable state of the selector (copyable by snapshot/restore)."""

    n_events: int
    buf: _Chunk
    chunks: list = field(default_factory=list)
    prev_window: _Chunk | None = None
    ref_pts: np.ndarray | None = None
    cur_pts: np.ndarray | None = None
    alive: np.ndarray | None = None
    prev8: np.ndarray | None = None
    t_ref_us: int = 0
    t_cur_us: int = 0
    n_frames: int = 0
    median_displacement_px: float = 0.0
    last_t_us: int | None = None
    """Time of the last event taken into a tiny window (the gap test looks across tiny windows too), us."""
    blank_us: int = 0
    """Time spanned by the tiny windows rejected for their event rate since the last dispatch, us."""
    hist_t: list = field(default_factory=list)
    """Mean event time of each tiny frame of the current reference, us (kept only when tracks are carried)."""
    hist_pts: list = field(default_factory=list)
    """Positions of all reference features in each of those frames, float32 (M, 2) px (only when carried)."""
    carried: _Carried | None = None
    """The previous window's features, continued through this one (only when carried)."""


def mean_time_us(t: np.ndarray) -> int:
    """``int(np.mean(t))`` of int64 event times, us, from an integer sum where that is exact: while ``n * max|t|``
    stays below 2^53 every partial sum of numpy's float64 summation is an integer it holds exactly, so its sum (in
    any order) is the integer sum and the mean the same one division. numpy's mean of int64 casts the array to
    float64 in buffered blocks, 75 us per tiny frame of the landing (session 26); else it is still used."""
    n = len(t)
    if n and max(abs(int(t.min())), abs(int(t.max()))) * n < 2**53:
        return int(float(int(t.sum())) / n)
    return int(np.mean(t))


def _empty_chunk() -> _Chunk:
    return _Chunk(np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int8))


def _cat(chunks: list[_Chunk]) -> _Chunk:
    if not chunks:
        return _empty_chunk()
    return _Chunk(*(np.concatenate([getattr(c, k) for c in chunks]) for k in "txyp"))


class EventWindowSelector:
    """Algorithm 1 as an explicit state machine; ``push`` returns the reconstruction windows completed."""

    def __init__(self, window: EventWindowConfig, features: FeatureConfig, image: EventImageConfig, width: int, height: int, seed: int = 0,
                 carry_tracks: bool = False):
        self.cfg = window
        self.carry_tracks = bool(carry_tracks)
        """Track each window's features on through the next window, so that window gets tracks from its start
        (``ReconstructionWindow.whole_pts``): one more KLT pass per tiny frame."""
        self.fcfg = features
        self.icfg = image
        self.width = int(width)
        self.height = int(height)
        self.seed = int(seed)
        self.state = WindowState(n_events=int(window.initial_events), buf=_empty_chunk())
        self.last_tiny_image: np.ndarray | None = None
        """Last tiny frame (float32 splat), for the viewer."""
        self.last_event = WindowEvent.WAITING
        self.n_events_history: list[int] = [self.state.n_events]
        """``N_e`` after every dispatch, events."""

    @property
    def n_events(self) -> int:
        """Current tiny-window size ``N_e``, events."""
        return self.state.n_events

    def snapshot(self) -> WindowState:
        import copy

        return copy.deepcopy(self.state)

    def restore(self, state: WindowState) -> None:
        import copy

        self.state = copy.deepcopy(state)

    # ------------------------------------------------------------------ input
    def push(self, t: np.ndarray, x: np.ndarray, y: np.ndarray, p: np.ndarray) -> list[ReconstructionWindow]:
        s = self.state
        if len(t):
            s.buf = _cat([s.buf, _Chunk(np.asarray(t, np.int64), np.asarray(x, np.float64), np.asarray(y, np.float64), np.asarray(p, np.int8))])
        out: list[ReconstructionWindow] = []
        while len(s.buf.t) >= s.n_events:
            n = s.n_events
            tiny = _Chunk(s.buf.t[:n], s.buf.x[:n], s.buf.y[:n], s.buf.p[:n])
            s.buf = _Chunk(s.buf.t[n:], s.buf.x[n:], s.buf.y[n:], s.buf.p[n:])
            k = self._after_gap(tiny.t)
            if k is not None:
                # A dropout: nothing before the gap may share an MCI with what follows it. The events after the gap
                # go back to the buffer and start a fresh tiny window.
                self._reset(keep_overlap=False)
                s.buf = _cat([_Chunk(tiny.t[k:], tiny.x[k:], tiny.y[k:], tiny.p[k:]), s.buf])
                s.last_t_us = int(tiny.t[k])
                self.last_event = WindowEvent.GAP
                continue
            s.last_t_us = int(tiny.t[-1])
            rw = self._process_tiny(tiny)
            if rw is not None:
                out.append(rw)
        if not out and len(s.buf.t) < s.n_events and self.last_event is WindowEvent.DISPATCHED:
            self.last_event = WindowEvent.WAITING
        return out

    def flush(self) -> ReconstructionWindow | None:
        """End of the stream: the events after the last reconstruction window as one more, forced window (no ``N_e``
        adaptation), or None. The partial tiny window left in the buffer goes through the tests of any tiny window
        (rate, features, KLT) when it holds at least half of ``N_e`` events, else it is dropped; the window is emitted
        when its own events (without the overlap) number at least ``flush_min_fraction`` of the previous window's
        own part, so a few stray events do not make an MCI. Needs a previous window (its overlap) and a reference."""
        s, frac = self.state, self.cfg.flush_min_fraction
        if frac <= 0 or s.prev_window is None:
            return None
        if len(s.buf.t):
            tiny, s.buf = s.buf, _empty_chunk()
            if 2 * len(tiny.t) >= s.n_events and self._after_gap(tiny.t) is None:
                s.last_t_us = int(tiny.t[-1])
                rw = self._process_tiny(tiny)
                if rw is not None:
                    return rw
        if s.ref_pts is None or not s.chunks or s.prev_window is None:
            return None
        if sum(len(c.t) for c in s.chunks) < frac * len(s.prev_window.t):
            return None
        return self._dispatch(forced=True)

    def _after_gap(self, t: np.ndarray) -> int | None:
        """Index of the first event of ``t`` after the last gap longer than ``max_event_gap_ms``
        (counting the gap since the previous tiny window), else None."""
        lim = self.cfg.max_event_gap_ms
        if lim <= 0 or not len(t):
            return None
        prev = self.state.last_t_us
        d = np.diff(t, prepend=t[0] if prev is None else prev)
        big = np.flatnonzero(d > lim * 1e3)
        return int(big[-1]) if len(big) else None

    # --------------------------------------------------------------- stages
    def _reset(self, keep_overlap: bool) -> None:
        s = self.state
        s.prev_window = _cat(s.chunks) if keep_overlap and s.chunks else None
        s.carried = None
        if self.carry_tracks and s.prev_window is not None and s.alive is not None and s.prev8 is not None and len(s.hist_t):
            keep = np.flatnonzero(s.alive)
            s.carried = _Carried([*s.hist_t], [p[keep] for p in s.hist_pts], np.ones(len(keep), bool), s.prev8)
        s.hist_t, s.hist_pts = [], []
        s.chunks = []
        s.ref_pts = s.cur_pts = s.alive = s.prev8 = None
        s.n_frames = 0
        s.median_displacement_px = 0.0

    def _process_tiny(self, tiny: _Chunk) -> ReconstructionWindow | None:
        s, cfg = self.state, self.cfg
        dt_s = max(int(tiny.t[-1] - tiny.t[0]), 1) / 1e6
        rate = len(tiny.t) / (dt_s * self.width * self.height)  # eq. (6)
        if rate < cfg.min_event_rate:
            self.last_event = WindowEvent.LOW_RATE
            if s.n_frames >= cfg.max_tiny_frames and s.ref_pts is not None:
                s.blank_us += int(tiny.t[-1] - tiny.t[0])
                return self._dispatch(forced=True)
            # The tiny frames collected so far are dropped with this one: none of their time reaches an MCI.
            s.blank_us += int(tiny.t[-1] - (s.chunks[0].t[0] if s.chunks else tiny.t[0]))
            # Restart from the initial state: slow, noisy data must not blur the next MCI.
            self._reset(keep_overlap=False)
            return None
        img = event_image(tiny.x, tiny.y, tiny.p if self.icfg.use_polarity else None, self.width, self.height, self.icfg.sigma_px)
        self.last_tiny_image = img
        img8 = to_uint8(img)
        t_mid = mean_time_us(tiny.t)
        if s.ref_pts is None:
            pts = detect_features(img8, self.fcfg, max_total=cfg.reference_features, support=img)
            if len(pts) < cfg.min_features:
                self.last_event = WindowEvent.NO_TEXTURE
                self._reset(keep_overlap=False)
                return None
            s.ref_pts, s.cur_pts, s.alive = pts, pts.copy(), np.ones(len(pts), bool)
            s.prev8, s.t_ref_us, s.t_cur_us = img8, t_mid, t_mid
            s.chunks = [tiny]
            s.n_frames = 1
            self._record(img8, t_mid)
            self.last_event = WindowEvent.TRACKING
            return None
        s.chunks.append(tiny)
        s.n_frames += 1
        idx = np.flatnonzero(s.alive)
        c = s.carried if self.carry_tracks else None
        carried = None
        if c is not None and c.last8 is s.prev8:
            # The carried features move between the same two tiny frames: one KLT call for both sets (each point is
            # tracked on its own, so the positions are those of two calls) saves the image pyramids of a second call.
            cidx = np.flatnonzero(c.alive)
            (new, ok), (cnew, cok) = track_feature_sets(s.prev8, img8, [s.cur_pts[idx], c.pts[-1][cidx]], self.fcfg)
            carried = (cidx, cnew, cok)
        else:
            new, ok = track_features(s.prev8, img8, s.cur_pts[idx], self.fcfg)
        s.cur_pts[idx[ok]] = new[ok]
        s.alive[idx[~ok]] = False
        s.prev8, s.t_cur_us = img8, t_mid
        self._reject_outliers()
        self._record(img8, t_mid, carried)
        alive = np.flatnonzero(s.alive)
        if len(alive) < cfg.min_features:
            # Features vanished (large motion or texture change): dispatch what we have if it spans motion.
            if s.n_frames >= 2:
                return self._dispatch(forced=True)
            self._reset(keep_overlap=False)
            self.last_event = WindowEvent.NO_TEXTURE
            return None
        s.median_displacement_px = self._median_displacement(alive)
        if s.median_displacement_px > cfg.feature_displacement_px:
            return self._dispatch(forced=False)
        if s.n_frames >= cfg.max_tiny_frames * 4:
            # Bounded memory for a camera that emits events without moving its features (flicker, noise).
            return self._dispatch(forced=True)
        self.last_event = WindowEvent.TRACKING
        return None

    def _median_displacement(self, alive: np.ndarray) -> float:
        """``M_fd`` (eq. 7) of the live features ``alive`` (indices), px. One method, so that another measurement can
        drive the dispatch and eq. (8): session 27's true-displacement oracle (module notes) overrides it."""
        s = self.state
        return float(np.median(np.linalg.norm(s.cur_pts[alive] - s.ref_pts[alive], axis=1)))

    def _record(self, img8: np.ndarray, t_mid: int, tracked: tuple | None = None) -> None:
        """Keeps this tiny frame's feature positions and moves the carried features into it (``carry_tracks``);
        ``tracked``: their KLT result (indices, positions, ok), when already tracked with the window's own features."""
        if not self.carry_tracks:
            return
        s = self.state
        s.hist_t.append(t_mid)
        s.hist_pts.append(s.cur_pts.copy())
        c = s.carried
        if c is None:
            return
        if tracked is None:
            idx = np.flatnonzero(c.alive)
            new, ok = track_features(c.last8, img8, c.pts[-1][idx], self.fcfg)
        else:
            idx, new, ok = tracked
        pts = c.pts[-1].copy()
        pts[idx[ok]] = new[ok]
        c.alive[idx[~ok]] = False
        c.t_us.append(t_mid)
        c.pts.append(pts)
        c.last8 = img8

    def _whole_tracks(self) -> tuple[np.ndarray, np.ndarray]:
        """The carried tracks alive through every frame, outliers to the epipolar geometry of their first and last
        frames removed, (F, M, 2) float32 px and (F,) int64 us."""
        c = self.state.carried
        if c is None or not c.alive.any():
            return np.zeros((0, 0, 2), np.float32), np.zeros(0, np.int64)
        pts = np.stack(c.pts)[:, c.alive]
        a, b = pts[0], pts[-1]
        if len(a) >= 12 and np.median(np.linalg.norm(a - b, axis=1)) >= 1.0:
            cv2.setRNGSeed(self.seed)
            _, mask = cv2.findFundamentalMat(a, b, cv2.FM_RANSAC, 1.0, 0.999)
            if mask is not None:
                pts = pts[:, mask.ravel() == 1]
        return np.ascontiguousarray(pts, np.float32), np.asarray(c.t_us, np.int64)

    def _reject_outliers(self) -> None:
        """RANSAC on the fundamental matrix between reference and current features (the two-view test of Algorithm 1)."""
        s = self.state
        alive = np.flatnonzero(s.alive)
        if len(alive) < 12:
            return
        a, b = s.ref_pts[alive], s.cur_pts[alive]
        if np.median(np.linalg.norm(a - b, axis=1)) < 1.0:
            return  # too little motion: F is degenerate, keep the KLT verdict
        cv2.setRNGSeed(self.seed)
        _, mask = cv2.findFundamentalMat(a, b, cv2.FM_RANSAC, 1.0, 0.999)
        if mask is not None:
            s.alive[alive[mask.ravel() == 0]] = False

    def _incoherent(self) -> bool:
        """Whether the window's feature displacement is KLT noise rather than motion (``EventWindowConfig.
        noise_residual_px``): the median distance of the tracks from a similarity fitted to all of them (least median of
        squares) exceeds the limit. Tiny frames of a few hundred events make KLT jitter by as much as ``th_fd``."""
        lim, s = self.cfg.noise_residual_px, self.state
        if lim <= 0 or s.alive is None or s.alive.sum() < 4:
            return False
        a, b = s.ref_pts[s.alive], s.cur_pts[s.alive]
        cv2.setRNGSeed(self.seed)
        M, _ = cv2.estimateAffinePartial2D(a, b, method=cv2.LMEDS)
        if M is None:
            return False
        return bool(np.median(np.linalg.norm(a @ M[:, :2].T + M[:, 2] - b, axis=1)) > lim)

    def _dispatch(self, forced: bool) -> ReconstructionWindow:
        s, cfg = self.state, self.cfg
        cur = _cat(s.chunks)
        parts = []
        if s.prev_window is not None and cfg.overlap > 0 and len(s.prev_window.t):
            k = int(round(len(s.prev_window.t) * min(cfg.overlap / (1.0 - cfg.overlap), 1.0)))
            if k > 0:
                pw = s.prev_window
                parts.append(_Chunk(pw.t[-k:], pw.x[-k:], pw.y[-k:], pw.p[-k:]))
        parts.append(cur)
        ev = _cat(parts)
        alive = s.alive if s.alive is not None else np.zeros(0, bool)
        whole_pts, whole_t = self._whole_tracks() if parts[:-1] else (np.zeros((0, 0, 2), np.float32), np.zeros(0, np.int64))
        rw = ReconstructionWindow(
            t=ev.t, x=ev.x, y=ev.y, p=ev.p,
            ref_pts=s.ref_pts[alive].copy() if s.ref_pts is not None else np.zeros((0, 2), np.float32),
            cur_pts=s.cur_pts[alive].copy() if s.cur_pts is not None else np.zeros((0, 2), np.float32),
            t_ref_us=s.t_ref_us, t_cur_us=s.t_cur_us, n_frames=s.n_frames,
            median_displacement_px=s.median_displacement_px, forced=forced, blank_us=s.blank_us,
            whole_pts=whole_pts, whole_t_us=whole_t, n_overlap=len(ev.t) - len(cur.t),
        )
        s.blank_us = 0
        if not forced and cfg.adapt_events and not self._incoherent():
            # eq. (8): fewer frames than expected -> the camera is fast -> smaller tiny windows, and vice versa.
            n_new = (s.n_frames * s.n_events) // cfg.expected_frames
            s.n_events = int(np.clip(n_new, cfg.min_events, cfg.max_events))
            self.n_events_history.append(s.n_events)
        self._reset(keep_overlap=True)
        self.last_event = WindowEvent.DISPATCHED
        return rw


# Why no MCI came out of a step, in plain words (the SLAM step's reason while waiting).
WINDOW_REASONS = {
    WindowEvent.WAITING: "collecting events",
    WindowEvent.LOW_RATE: "event rate below th_e (camera still or too slow)",
    WindowEvent.GAP: "no events for longer than max_event_gap_ms (dropout): window restarted",
    WindowEvent.NO_TEXTURE: "too few features in the tiny frames (no texture)",
    WindowEvent.TRACKING: "tracking features in tiny frames",
    WindowEvent.DISPATCHED: "",
}
