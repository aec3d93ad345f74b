"""Time plots (uplot): pose error vs ground truth, latency per module, event rate, inliers, share filtered.

Each plot shows a bounded window of the latest steps, so an update costs the
same at minute 10 as at second 1 (the history itself is never resent).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from app.engine import Engine, EventsOnlyEngine
from app.frame import Frame, StepSummary
from evpose.core.trajectory import Trajectory
from evpose.eval.sim3_alignment import Sim3

WINDOW_STEPS = 400
"""Steps kept in each plot."""

Y_AXIS_PX = 60
"""Width of each plot's y-axis labels, CSS pixels."""

PALETTE = ("#e6550d", "#3182bd", "#31a354", "#756bb1", "#636363", "#d6616b", "#8ca252", "#bd9e39")


class GroundTruthLookup:
    """Ground truth prepared once for fast interpolation at many step times (position linear, rotation slerp)."""

    def __init__(self, gt: Trajectory):
        self.t = gt.t.astype(np.float64)
        self.position = gt.position
        self._slerp = Slerp(self.t, gt.rotation) if len(gt) > 1 else None
        self._rot0 = gt.rotation[0] if len(gt) else None

    def __call__(self, t_us: np.ndarray) -> tuple[np.ndarray, Rotation]:
        tc = np.clip(np.asarray(t_us, np.float64), self.t[0], self.t[-1])
        if self._slerp is None:
            return np.repeat(self.position[:1], tc.size, 0), Rotation.concatenate([self._rot0] * tc.size)
        pos = np.stack([np.interp(tc, self.t, self.position[:, k]) for k in range(3)], axis=1)
        return pos, self._slerp(tc)


_LOOKUPS: dict[int, tuple[Trajectory, GroundTruthLookup]] = {}


def _lookup(gt: Trajectory) -> GroundTruthLookup:
    # Keyed by identity: a recording's ground truth is immutable while it is loaded.
    hit = _LOOKUPS.get(id(gt))
    if hit is None or hit[0] is not gt:
        _LOOKUPS.clear()
        hit = _LOOKUPS[id(gt)] = (gt, GroundTruthLookup(gt))
    return hit[1]


PLOT_GAP_US = 1_000_000
"""Steps further apart than this (an event gap the tracker's steps skip) start the plots afresh, microseconds."""

POSE_ERROR = "pose error"
SLAM_POSE_ERROR = "position error (maps aligned to ground truth)"
"""SLAM mode's pose-error plot: each step's position mapped by its map's alignment (as the 3D view's *slam aligned*).
Position only: the alignment fits positions (evo's Umeyama, as ``evpose eval --atlas --correct-scale``), and over
the short, nearly straight stretch a map covers it leaves the rotation about the direction of travel loose; on the
demo landing (``demo_data/landing.h5``, SLAM seeked to 1.2 s) the rotation after it was 91-102 deg off while the
positions were 10-38 cm off, a figure of the alignment rather than of SLAM."""


def _pose_in_ground_truth(step: StepSummary, alignments: dict[int, Sim3] | None) -> np.ndarray | None:
    """The step's pose in the ground truth's frame: as it is, or (SLAM) through its map's alignment (None if that map has none)."""
    if step.pose is None or alignments is None:
        return step.pose
    alignment = alignments.get(step.counts.get("map_id", -1))
    return None if alignment is None else alignment.poses(step.pose)


def pose_errors(history: list[StepSummary], gt: Trajectory | None,
                alignments: dict[int, Sim3] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Position error (m) and rotation error (rad) of each step's pose against interpolated ground truth; NaN where unknown.

    ``alignments`` (SLAM mode): map id -> its Sim(3)/SE(3) alignment to the ground truth; a step's pose
    (``counts["map_id"]``, in that map's own frame and scale) is compared after it, and is unknown without one.
    """
    n = len(history)
    pos_err = np.full(n, np.nan)
    rot_err = np.full(n, np.nan)
    poses = [_pose_in_ground_truth(s, alignments) for s in history]
    idx = [i for i, pose in enumerate(poses) if pose is not None]
    if gt is None or len(gt) == 0 or not idx:
        return pos_err, rot_err
    t = np.array([history[i].t_us for i in idx])
    inside = (t >= gt.t[0]) & (t <= gt.t[-1])
    if not inside.any():
        return pos_err, rot_err
    idx = [i for i, ok in zip(idx, inside) if ok]
    ref_pos, ref_rot = _lookup(gt)(t[inside])
    est = np.stack([poses[i] for i in idx])
    pos_err[idx] = np.linalg.norm(est[:, :3, 3] - ref_pos, axis=1)
    rot_err[idx] = (ref_rot.inv() * Rotation.from_matrix(est[:, :3, :3])).magnitude()
    return pos_err, rot_err


def plot_series(history: list[StepSummary], gt: Trajectory | None, window: int = WINDOW_STEPS,
                alignments: dict[int, Sim3] | None = None, t0_us: int = 0) -> dict[str, tuple[tuple[str, ...], tuple[np.ndarray, ...]]]:
    """Plot name -> (series labels, (t_seconds, y1, y2, ...)) over the last ``window`` steps (``alignments``: SLAM mode,
    see :func:`pose_errors`; ``t0_us``: the recording's start, the time axis counts from it as the time slider)."""
    h = history[-window:]
    t_us = np.array([s.t_us for s in h], np.int64)
    jumps = np.flatnonzero(np.diff(t_us) > PLOT_GAP_US)
    if len(jumps):
        # The tracker's steps skip a long event gap: drawn across it, the steps after a 60 s gap were squeezed into
        # the right edge of a 60 s axis, joined to those before by a straight line through the gap.
        h, t_us = h[jumps[-1] + 1:], t_us[jumps[-1] + 1:]
    t = (t_us - int(t0_us)) / 1e6
    out: dict[str, tuple[tuple[str, ...], tuple[np.ndarray, ...]]] = {}
    pe, re = pose_errors(h, gt, alignments)
    if alignments is None:
        out[POSE_ERROR] = (("position [cm]", "rotation [deg]"), (t, pe * 100.0, np.degrees(re)))
    else:
        out[SLAM_POSE_ERROR] = (("position [cm]",), (t, pe * 100.0))
    modules = sorted({k for s in h for k in s.timings_ms})
    if modules:
        # A run's first step also loads the compiled kernels (0.3 s here; ~30 s on a cold numba cache, and a
        # prepared recording keeps the warm-up process's): drawn, it flattened every other step of the first
        # window to the axis. It is left out of the plot (the step's summary keeps it).
        first = np.array([s.index == 0 for s in h])
        out["latency per module [ms]"] = (tuple(modules), (t, *[np.where(first, np.nan, np.array([s.timings_ms.get(m, np.nan) for s in h], np.float64))
                                                                for m in modules]))
    ev = np.array([s.counts.get("events_in", 0) for s in h], np.float64)
    # Each step's events arrived since the previous step; the first step assumes the usual spacing.
    first_dt = (t[1] - t[0]) if len(t) > 1 else 0.01
    dt = np.diff(t, prepend=t[0] - first_dt) if len(t) else np.zeros(0)
    # In thousands: "150,000" does not fit uplot's y-axis labels (drawn "0,000").
    out["events per second"] = (("k events/s",), (t, np.divide(ev / 1e3, dt, out=np.full_like(ev, np.nan), where=dt > 0)))
    if alignments is None:
        inl = np.array([s.counts.get("inliers", np.nan) for s in h], np.float64)
        used = np.array([s.counts.get("points_used", np.nan) for s in h], np.float64)
        out["inliers"] = (("inliers", "points used"), (t, inl, used))
    else:  # SLAM registers no map points: what it tracks instead
        tracks = np.array([s.counts.get("tracks", np.nan) for s in h], np.float64)
        points = np.array([s.counts.get("map_points", np.nan) for s in h], np.float64)
        out["tracks and map points"] = (("tracked features", "map points"), (t, tracks, points))
    kept = np.array([s.counts.get("events_kept", np.nan) for s in h], np.float64)
    share = np.divide(ev - kept, ev, out=np.full_like(ev, np.nan), where=ev > 0)
    out["share filtered"] = (("removed [%]",), (t, 100.0 * share))
    return out


NICE_MULTIPLES = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0)
"""Round tops of a y range, times a power of ten (1-2-5 alone left half the plot empty above 101 cm: range 0-220)."""


MIN_X_SPAN_S = 0.05
"""The time axis spans at least this long, seconds: over a recording's first step or two (a 1 ms span) uplot's ticks
all read '0.036'."""


def x_range(t: np.ndarray) -> tuple[float, float]:
    """The time axis spans the window's steps, at least :data:`MIN_X_SPAN_S` from the first."""
    if not len(t):
        return (0.0, MIN_X_SPAN_S)
    t0, t1 = float(t[0]), float(t[-1])
    return (t0, max(t1, t0 + MIN_X_SPAN_S))


def y_range(ys: tuple[np.ndarray, ...]) -> tuple[float, float]:
    """The y-axis range a plot is drawn with: from 0 (or the lowest value) to 10 % above a round number just above
    the highest (the round number's tick label, drawn at the very top, was cut in half).

    Set here, not by uplot: uplot's auto range came out empty when any series started with a NaN (a step without
    the value), and drew nothing, axes included: the latency plot while the first step (left out) was in its window,
    SLAM's pose error before its first map. Round, so it changes rarely (a new range rebuilds the chart).
    """
    finite = [y[np.isfinite(y)] for y in ys]
    values = np.concatenate(finite) if finite else np.zeros(0)
    lo = min(0.0, float(values.min())) if values.size else 0.0
    span = float(values.max()) * 1.02 - lo if values.size else 1.0
    if span <= 0:
        return lo, lo + 1.1
    step = 10.0 ** np.floor(np.log10(span))
    nice = next((m * step for m in NICE_MULTIPLES if span <= m * step * (1 + 1e-12)), 10.0 * step)
    return lo, lo + 1.1 * nice


def empty_reasons(series: dict[str, tuple[tuple[str, ...], tuple[np.ndarray, ...]]], history: list[StepSummary],
                  gt: Trajectory | None, note: str = "") -> dict[str, str]:
    """Plot name -> why it has nothing to draw, in one line, for the plots of ``series`` without two values in a series.

    ``note``: the engine's explanation when it makes no poses (events-only view: no map, or tracking/SLAM cannot start).
    """
    out = {}
    for name, (_, data) in series.items():
        # One value in many steps draws no line either (the events-only view times only the step a seek lands on);
        # a first step alone is drawn as the dot it is.
        if len(data[0]) < 2 or max((int(np.isfinite(y).sum()) for y in data[1:]), default=0) >= 2:
            continue
        if name in (POSE_ERROR, SLAM_POSE_ERROR) and (gt is None or len(gt) < 2):
            why = "this recording has no ground truth to compare with."
        elif name.startswith("latency") and all(s.index == 0 or s.timings_ms for s in history[-WINDOW_STEPS:]):
            # Step 1 after opening (SLAM mode, session 28) was told "the steps a seek went past", without a seek.
            why = "one step timed so far (a run's first step is left out: it loads the compiled kernels); play or step forward to draw the line."
        elif name.startswith("latency"):
            why = "the steps a seek went past were not timed; play or step forward to time them."
        elif note and all(s.pose is None for s in history[-WINDOW_STEPS:]):
            # The whole explanation once, under the first plot it empties.
            why = f"no poses in this view. {note}" if name in (POSE_ERROR, SLAM_POSE_ERROR) else "no registration in this view (see pose error)."
        elif name == SLAM_POSE_ERROR:
            why = ("no SLAM position aligned to the ground truth in these steps (a map is aligned once it has "
                   "3 poses inside the ground truth's time span; before that SLAM is initialising).")
        elif name == POSE_ERROR:
            why = "no pose in these steps (the tracker is lost)."
        else:
            why = "no values in these steps."
        out[name] = why
    return out


def plot_context(frame: Frame, engine: Engine) -> tuple[dict | None, str]:
    """What the plots need beyond the history: SLAM mode's alignment of each map to the ground truth (the pose error
    is measured after it; None outside SLAM mode), and why an events-only view has no poses."""
    alignments = None if frame.slam is None else {v.map_id: v.alignment for v in frame.slam.atlas if v.alignment is not None}
    return alignments, engine.explanation if isinstance(engine, EventsOnlyEngine) else ""


PLOT_ORDER = (POSE_ERROR, SLAM_POSE_ERROR, "latency per module [ms]", "events per second", "inliers",
              "tracks and map points", "share filtered")
"""Places of the plots in their tab, top to bottom (a mode's pose error first; one of each pair is shown)."""


class PlotsView:
    """uplot handles, created on first use and never removed; a plot with nothing to draw is hidden and replaced by
    a line saying why (an empty frame of axes told the user nothing).

    Never removed (hidden instead, and reused): viser's browser code applies a batch's property updates after its
    removals, so the plot updates sent just before a recording switch while playing were applied to removed plots
    ("Tried to update non-existent component ... {data}" in the browser console, 140 in a 12-minute session). A
    plot's series change (other latency modules) shows another plot made for those series; there are a few per name.
    """

    def __init__(self, gui, container=None):
        self.gui = gui
        self.container = container
        """Tab or folder the plots live in (new plots are added inside it)."""
        self.handles: dict[str, tuple[tuple[str, ...], object]] = {}
        """Plot name -> (series labels, handle) of the plot shown (or last shown) under that name."""
        self.notes: dict[str, object] = {}
        """Plot name -> markdown saying why the plot is empty, shown in its place."""
        self._made: dict[tuple[str, tuple[str, ...]], object] = {}
        """(plot name, series labels) -> every plot made, hidden when not shown."""

    def _add(self, add, *args, **kwargs):
        if self.container is not None:
            with self.container:
                return add(*args, **kwargs)
        return add(*args, **kwargs)

    def update(self, history: list[StepSummary], gt: Trajectory | None, alignments: dict[int, Sim3] | None = None,
               note: str = "", t0_us: int = 0) -> None:
        """Draw the plots of the latest window (``alignments``, ``note``: see :func:`plot_series`, :func:`empty_reasons`)."""
        from viser import uplot

        series = plot_series(history, gt, alignments=alignments, t0_us=t0_us)
        reasons = empty_reasons(series, history, gt, note)
        for name, (labels, data) in series.items():
            order = float(PLOT_ORDER.index(name) if name in PLOT_ORDER else len(PLOT_ORDER) + list(series).index(name))
            known = self.handles.get(name)
            why = reasons.get(name)
            text = f"**{name}**: {why}" if why else ""
            shown = self.notes.get(name)
            if why and shown is None:
                self.notes[name] = self._add(self.gui.add_markdown, text, order=order)
            elif shown is not None:
                if shown.content != text:
                    shown.content = text
                if shown.visible != bool(why):
                    shown.visible = bool(why)
            if why:
                if known is not None and known[1].visible:
                    known[1].visible = False
                continue
            data = tuple(np.ascontiguousarray(d, np.float64) for d in data)
            # The x range is sent, not left to uplot: viser's client keeps the x bounds relative to the old data's
            # and after a seek then play they drifted off the window (at 3.99 s the axis read 1.0-1.9 s, empty).
            scales = {"x": uplot.Scale(time=False, auto=False, range=x_range(data[0])),
                      "y": uplot.Scale(auto=False, range=y_range(data[1:]))}
            if known is not None and known[0] != labels:
                if known[1].visible:
                    known[1].visible = False
                known = None
            handle = known[1] if known is not None else self._made.get((name, labels))
            if handle is not None:
                if any(handle.scales[k]["range"] != scales[k]["range"] for k in scales):
                    handle.scales = scales
                handle.data = data
                if not handle.visible:
                    handle.visible = True
                self.handles[name] = (labels, handle)
                continue
            series_spec = (uplot.Series(label="t [s]"),) + tuple(
                uplot.Series(label=lab, stroke=PALETTE[i % len(PALETTE)], width=1.5) for i, lab in enumerate(labels))
            # A y-axis wide enough for "1,000" and "0.005" (uplot's default cuts five-character labels).
            kwargs = dict(title=name, scales=scales, aspect=2.2, legend=uplot.Legend(show=True),
                          axes=(uplot.Axis(), uplot.Axis(size=Y_AXIS_PX)), order=order)
            handle = self._made[(name, labels)] = self._add(self.gui.add_uplot, data, series_spec, **kwargs)
            self.handles[name] = (labels, handle)

    def clear(self) -> None:
        """Hide every plot and note (a recording is being opened); the next :meth:`update` shows its own."""
        for handle in (*self._made.values(), *self.notes.values()):
            if handle.visible:
                handle.visible = False
