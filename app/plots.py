"""Time plots (uplot): pose error vs ground truth, latency per module, event rate, inliers, share filtered.

Each plot shows a bounded window of the latest steps, so an update costs the
same at minute 10 as at second 1 (the history itself is never resent).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from app.frame import StepSummary
from evpose.core.trajectory import Trajectory

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


def pose_errors(history: list[StepSummary], gt: Trajectory | None) -> tuple[np.ndarray, np.ndarray]:
    """Position error (m) and rotation error (rad) of each step's pose against interpolated ground truth; NaN where unknown."""
    n = len(history)
    pos_err = np.full(n, np.nan)
    rot_err = np.full(n, np.nan)
    idx = [i for i, s in enumerate(history) if s.pose is not None]
    if gt is None or len(gt) == 0 or not idx:
        return pos_err, rot_err
    t = np.array([history[i].t_us for i in idx])
    inside = (t >= gt.t[0]) & (t <= gt.t[-1])
    if not inside.any():
        return pos_err, rot_err
    idx = [i for i, ok in zip(idx, inside) if ok]
    ref_pos, ref_rot = _lookup(gt)(t[inside])
    est = np.stack([history[i].pose for i in idx])
    pos_err[idx] = np.linalg.norm(est[:, :3, 3] - ref_pos, axis=1)
    rot_err[idx] = (ref_rot.inv() * Rotation.from_matrix(est[:, :3, :3])).magnitude()
    return pos_err, rot_err


def plot_series(history: list[StepSummary], gt: Trajectory | None, window: int = WINDOW_STEPS) -> dict[str, tuple[tuple[str, ...], tuple[np.ndarray, ...]]]:
    """Plot name -> (series labels, (t_seconds, y1, y2, ...)) over the last ``window`` steps."""
    h = history[-window:]
    t = np.array([s.t_us for s in h], np.float64) / 1e6
    out: dict[str, tuple[tuple[str, ...], tuple[np.ndarray, ...]]] = {}
    pe, re = pose_errors(h, gt)
    out["pose error"] = (("position [cm]", "rotation [deg]"), (t, pe * 100.0, np.degrees(re)))
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
    inl = np.array([s.counts.get("inliers", np.nan) for s in h], np.float64)
    used = np.array([s.counts.get("points_used", np.nan) for s in h], np.float64)
    out["inliers"] = (("inliers", "points used"), (t, inl, used))
    kept = np.array([s.counts.get("events_kept", np.nan) for s in h], np.float64)
    share = np.divide(ev - kept, ev, out=np.full_like(ev, np.nan), where=ev > 0)
    out["share filtered"] = (("removed [%]",), (t, 100.0 * share))
    return out


class PlotsView:
    """uplot handles, created on first use and recreated only when a plot's series change."""

    def __init__(self, gui, container=None):
        self.gui = gui
        self.container = container
        """Tab or folder the plots live in (new plots are added inside it)."""
        self.handles: dict[str, tuple[tuple[str, ...], object]] = {}

    def update(self, history: list[StepSummary], gt: Trajectory | None) -> None:
        from viser import uplot

        for name, (labels, data) in plot_series(history, gt).items():
            data = tuple(np.ascontiguousarray(np.nan_to_num(d, nan=np.nan), np.float64) for d in data)
            known = self.handles.get(name)
            if known is not None and known[0] == labels:
                known[1].data = data
                continue
            if known is not None:
                known[1].remove()
            series = (uplot.Series(label="t [s]"),) + tuple(
                uplot.Series(label=lab, stroke=PALETTE[i % len(PALETTE)], width=1.5) for i, lab in enumerate(labels))
            # A y-axis wide enough for "1,000" and "0.005" (uplot's default cuts five-character labels).
            kwargs = dict(title=name, scales={"x": uplot.Scale(time=False, auto=True)}, aspect=2.2, legend=uplot.Legend(show=True),
                          axes=(uplot.Axis(), uplot.Axis(size=Y_AXIS_PX)))
            if self.container is not None:
                with self.container:
                    handle = self.gui.add_uplot(data, series, **kwargs)
            else:
                handle = self.gui.add_uplot(data, series, **kwargs)
            self.handles[name] = (labels, handle)

    def remove(self) -> None:
        for _, h in self.handles.values():
            h.remove()
        self.handles.clear()
