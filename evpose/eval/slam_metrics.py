"""Metrics of the event-SLAM paper over an atlas of disconnected maps (eqs. 9 and 10), computed with evo.

- **Normalised RPE** (eq. 9): per map, the mean RPE between consecutive
  estimates (evo, delta = 1 frame) after aligning the map to ground truth
  (Umeyama with scale for event-only runs, without for inertial runs), divided
  by the map's travelled distance; then averaged over the maps. Translation:
  metres per metre (unitless); rotation: degrees per metre.
- **Stability** (eq. 10): tracked time ``tau(t)`` (s) and travelled distance
  ``tau(p)`` (m) summed over the maps; the paper's stability column is their
  product (m s). The distance uses ground-truth positions at the estimate
  times, because event-only maps have no metric scale of their own.
- **ATE** of each aligned map, and as a share of its travelled distance.
- **Time per status** (:func:`status_durations_s`): how much of the recording each
  step status covers. A map's tracked time counts every pose it holds, coasted
  ones (event-only, no visual fix) included; the share under ``ok`` is the time
  actually tracked from the events.
- **Scale drift** of each map: the map is cut into segments of ``segment_s``
  seconds, each is Sim(3)-aligned to ground truth on its own, and the spread of
  the segment scales (largest over smallest, minus one) says how far the map's
  scale wandered; a metric map should also have segment scales near 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError


@dataclass
class MapMetrics:
    """Figures of one map of the atlas."""

    poses: int
    tracked_time_s: float
    """Time between the map's first and last estimate, s."""
    distance_m: float
    """Ground-truth path length over the map's estimates, m."""
    scale: float
    """Alignment scale (1 without scale correction)."""
    ate_m: float
    """RMS absolute position error after alignment, m."""
    rpe_trans_m: float
    """Mean RPE translation between consecutive estimates, m."""
    rpe_rot_deg: float
    """Mean RPE rotation between consecutive estimates, degrees."""
    segment_scales: list = field(default_factory=list)
    """Umeyama scale of each ``segment_s`` piece aligned on its own, metres per map unit (empty if no piece moved)."""

    @property
    def scale_drift_percent(self) -> float:
        """Spread of the segment scales, ``100 (max / min - 1)``, percent (NaN with fewer than two segments)."""
        s = [v for v in self.segment_scales if np.isfinite(v) and v > 0]
        return 100.0 * (max(s) / min(s) - 1.0) if len(s) >= 2 else float("nan")

    @property
    def ate_percent(self) -> float:
        return 100.0 * self.ate_m / self.distance_m if self.distance_m > 0 else float("nan")


@dataclass
class SlamMetrics:
    """Atlas-level figures (the paper's Table I columns plus ATE)."""

    maps: list[MapMetrics] = field(default_factory=list)
    duration_s: float = 0.0
    """Span of the ground truth (or recording) the run covered, s."""

    @property
    def rpe_trans_per_m(self) -> float:
        """Eq. (9), translation: mean over maps of RPE / distance (m/m)."""
        v = [m.rpe_trans_m / m.distance_m for m in self.maps if m.distance_m > 0]
        return float(np.mean(v)) if v else float("nan")

    @property
    def rpe_rot_deg_per_m(self) -> float:
        """Eq. (9), rotation: mean over maps of RPE / distance (deg/m)."""
        v = [m.rpe_rot_deg / m.distance_m for m in self.maps if m.distance_m > 0]
        return float(np.mean(v)) if v else float("nan")

    @property
    def tracked_time_s(self) -> float:
        return float(sum(m.tracked_time_s for m in self.maps))

    @property
    def distance_m(self) -> float:
        return float(sum(m.distance_m for m in self.maps))

    @property
    def stability(self) -> float:
        """Travelled distance x tracked time, m s (eq. 10, as in the paper's Table I)."""
        return self.tracked_time_s * self.distance_m

    @property
    def tracked_fraction(self) -> float:
        return self.tracked_time_s / self.duration_s if self.duration_s > 0 else 0.0

    @property
    def ate_percent(self) -> float:
        """Distance-weighted ATE share over maps, percent of travelled distance."""
        d = self.distance_m
        return float(100.0 * sum(m.ate_m for m in self.maps) / d) if d > 0 and self.maps else float("nan")

    def to_dict(self) -> dict:
        return {
            "maps": len(self.maps),
            "rpe_trans_per_m": self.rpe_trans_per_m,
            "rpe_rot_deg_per_m": self.rpe_rot_deg_per_m,
            "tracked_time_s": self.tracked_time_s,
            "distance_m": self.distance_m,
            "stability_m_s": self.stability,
            "tracked_fraction": self.tracked_fraction,
            "ate_percent": self.ate_percent,
            "ate_percent_max": max((m.ate_percent for m in self.maps), default=float("nan")),
            # None (JSON null), not NaN, where no map has two segments: summaries compare equal run to run.
            "scale_drift_percent_max": max((m.scale_drift_percent for m in self.maps if np.isfinite(m.scale_drift_percent)), default=None),
            "per_map": [vars(m) | {"ate_percent": m.ate_percent, "scale_drift_percent": _finite_or_none(m.scale_drift_percent)} for m in self.maps],
        }


def status_durations_s(t_us: np.ndarray, statuses: list[str], start_us: int, end_us: int) -> dict[str, float]:
    """Seconds of ``[start_us, end_us]`` under each step status: the span from the previous MCI (the first: from
    ``start_us``) to each MCI is credited to that MCI's status, whose window of events it covers; what follows the last
    MCI is credited to ``"none"`` (no MCI yet / any more). ``t_us`` must be sorted (one entry per MCI)."""
    t = np.asarray(t_us, np.int64)
    if t.ndim != 1 or len(t) != len(statuses):
        raise ValueError(f"status_durations_s: {t.shape} times for {len(statuses)} statuses")
    if len(t) > 1 and np.any(np.diff(t) < 0):
        raise ValueError("status_durations_s: MCI times must be sorted")
    edges = np.clip(np.concatenate(([start_us], t, [end_us])), start_us, max(start_us, end_us))
    spans = np.diff(edges) / 1e6
    out: dict[str, float] = {}
    for status, span in zip(list(statuses) + ["none"], spans):
        out[status] = out.get(status, 0.0) + float(span)
    return dict(sorted(out.items()))


def _finite_or_none(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _evo(traj: Trajectory):
    from evo.core.trajectory import PoseTrajectory3D

    return PoseTrajectory3D(positions_xyz=traj.position.copy(), orientations_quat_wxyz=traj.quat_xyzw[:, [3, 0, 1, 2]].copy(), timestamps=traj.t / 1e6)


def segment_scales(est_xyz: np.ndarray, ref_xyz: np.ndarray, t_us: np.ndarray, segment_s: float, min_poses: int = 5) -> list[float]:
    """Umeyama scale (ref per est unit) of consecutive ``segment_s`` pieces of a trajectory, each aligned on its own.

    Pieces with fewer than ``min_poses`` poses, or whose ground truth barely moves
    (under 1 % of the whole path's extent, where the scale is noise), are skipped.
    """
    from evo.core.geometry import GeometryException, umeyama_alignment

    if segment_s <= 0 or len(t_us) < min_poses:
        return []
    extent = float(np.linalg.norm(ref_xyz.max(axis=0) - ref_xyz.min(axis=0)))
    edges = np.arange(t_us[0], t_us[-1] + 1, int(segment_s * 1e6))
    out = []
    for a in edges:
        sel = (t_us >= a) & (t_us < a + int(segment_s * 1e6))
        if sel.sum() < min_poses:
            continue
        e, r = est_xyz[sel], ref_xyz[sel]
        if np.linalg.norm(r - r.mean(axis=0), axis=1).max() < 0.01 * extent:
            continue
        try:
            _, _, c = umeyama_alignment(e.T.copy(), r.T.copy(), with_scale=True)
        except GeometryException:
            continue
        out.append(float(c))
    return out


def map_metrics(est: Trajectory, gt: Trajectory, correct_scale: bool, segment_s: float = 0.5) -> MapMetrics | None:
    """Metrics of one map; None if it has fewer than three poses inside the ground truth's span or cannot be aligned.

    ``segment_s`` is the length of the pieces the scale drift is measured on, seconds.
    """
    from evo.core import metrics

    inside = (est.t >= gt.t[0]) & (est.t <= gt.t[-1])
    est = est[inside]
    if len(est) < 3:
        return None
    # Ground truth interpolated at the estimate times: exact association, no time tolerance to tune.
    ref = gt.interpolate(est.t)
    e, r = _evo(est), _evo(ref)
    from evo.core.geometry import GeometryException

    try:
        _, _, s = e.align(r, correct_scale=correct_scale)
    except GeometryException:
        return None  # a straight-line or single-point map cannot be aligned (Umeyama is degenerate)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((r, e))
    rpe_t = metrics.RPE(metrics.PoseRelation.translation_part, 1.0, metrics.Unit.frames, all_pairs=False)
    rpe_t.process_data((r, e))
    rpe_r = metrics.RPE(metrics.PoseRelation.rotation_angle_deg, 1.0, metrics.Unit.frames, all_pairs=False)
    rpe_r.process_data((r, e))
    dist = float(np.sum(np.linalg.norm(np.diff(ref.position, axis=0), axis=1)))
    scales = segment_scales(est.position, ref.position, est.t, segment_s)
    return MapMetrics(
        poses=len(est), tracked_time_s=float((est.t[-1] - est.t[0]) / 1e6), distance_m=dist, scale=float(s),
        ate_m=float(ape.get_statistic(metrics.StatisticsType.rmse)),
        rpe_trans_m=float(rpe_t.get_statistic(metrics.StatisticsType.mean)),
        rpe_rot_deg=float(rpe_r.get_statistic(metrics.StatisticsType.mean)),
        segment_scales=scales,
    )


def atlas_metrics(estimates: list[Trajectory], gt: Trajectory, correct_scale: bool, duration_s: float | None = None) -> SlamMetrics:
    """Eqs. (9)-(10) over the maps of an atlas (one trajectory per map) against one ground truth."""
    if gt is None or len(gt) < 2:
        raise InputError(None, "SLAM metrics need a ground truth with at least two poses")
    out = SlamMetrics(duration_s=float(duration_s if duration_s is not None else (gt.t[-1] - gt.t[0]) / 1e6))
    for est in estimates:
        mm = map_metrics(est, gt, correct_scale)
        if mm is not None:
            out.maps.append(mm)
    return out


def spread_summary(values: list[float], target: float) -> dict:
    """Mean, median, best and worst of one figure over runs (e.g. the ATE % of one scenario over simulator seeds), and how
    many runs meet ``target`` (value <= target). Event-only SLAM swings from run to run (a small change moves one seed's
    ATE from 2 % to 20 % and another's the other way), so changes are judged on this spread, not on one recording."""
    v = np.asarray([x for x in values if np.isfinite(x)], np.float64)
    if v.size == 0:
        return {"runs": 0, "mean": float("nan"), "median": float("nan"), "best": float("nan"), "worst": float("nan"), "within_target": 0}
    return {"runs": int(v.size), "mean": float(v.mean()), "median": float(np.median(v)), "best": float(v.min()), "worst": float(v.max()),
            "within_target": int(np.sum(v <= target))}
