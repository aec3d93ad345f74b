"""Errors per motion-speed bin, as in the EV-Pose paper's Fig. 15.

The paper bins translation speed into slow (< 2 m/s), moderate (2-4 m/s) and
fast (> 4 m/s), and rotation speed into slow (< 10 deg/s), moderate
(10-30 deg/s) and fast (> 30 deg/s). Speeds come from the ground truth (the
true motion, not the estimate's): translation speed by central differences of
positions over time, rotation speed as the angle of the relative rotation
between neighbouring ground-truth poses over their time gap. They are
evaluated at the associated timestamps by linear interpolation. An APE error
is binned by the speed at its pose; an RPE error by the speed at the second
pose of its pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.eval.metrics import EvalResult, error_stats

BIN_NAMES = ("slow", "moderate", "fast")


@dataclass(frozen=True)
class SpeedBinConfig:
    """Bin edges of the paper's slow / moderate / fast classes."""

    translation_edges_m_s: tuple[float, float] = (2.0, 4.0)
    """Upper edges of the slow and moderate translation bins, m/s."""
    rotation_edges_deg_s: tuple[float, float] = (10.0, 30.0)
    """Upper edges of the slow and moderate rotation bins, deg/s."""


def ground_truth_speeds(gt: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times s, translation speed m/s, rotation speed deg/s) at every ground-truth pose."""
    t = gt.t.astype(np.float64) / 1e6
    if len(gt) < 2:
        return t, np.zeros(len(gt)), np.zeros(len(gt))
    v = np.gradient(gt.position, t, axis=0)
    trans = np.linalg.norm(v, axis=1)
    rot = gt.rotation
    # Angle of each consecutive relative rotation over its gap, then the
    # per-pose rate as the mean of the two adjacent gaps (one at the ends).
    step_deg = np.degrees((rot[:-1].inv() * rot[1:]).magnitude()) / np.diff(t)
    omega = np.empty(len(gt))
    omega[0], omega[-1] = step_deg[0], step_deg[-1]
    omega[1:-1] = 0.5 * (step_deg[:-1] + step_deg[1:])
    return t, trans, omega


def _bin(values: np.ndarray, edges: tuple[float, float]) -> np.ndarray:
    """0/1/2 for slow/moderate/fast; a value on an edge goes to the faster bin."""
    return np.searchsorted(np.asarray(edges, dtype=np.float64), values, side="right")


def speed_bins(result: EvalResult, gt: Trajectory, config: SpeedBinConfig = SpeedBinConfig()) -> dict:
    """Statistics of ATE/ARE/RTE/RRE per translation-speed and rotation-speed bin.

    Returns ``{"translation": {bin: {"ate_m": stats, ...}}, "rotation": {...},
    "edges": {...}}`` where each ``stats`` is :func:`error_stats` (``n`` = 0 for an
    empty bin). ``gt`` is the full ground truth the result was computed against;
    with a time offset in the config, the estimate clock is shifted back to GT time.
    """
    t_gt, v_gt, w_gt = ground_truth_speeds(gt)
    t_q = result.timestamps_s + result.config.time_offset_s
    v = np.interp(t_q, t_gt, v_gt)
    w = np.interp(t_q, t_gt, w_gt)
    out: dict = {
        "edges": {
            "translation_m_s": list(config.translation_edges_m_s),
            "rotation_deg_s": list(config.rotation_edges_deg_s),
        }
    }
    for kind, speed, edges in (("translation", v, config.translation_edges_m_s), ("rotation", w, config.rotation_edges_deg_s)):
        pose_bin = _bin(speed, edges)
        pair_bin = pose_bin[result.rpe_index] if result.rpe_index.size else np.zeros(0, np.int64)
        table = {}
        for b, name in enumerate(BIN_NAMES):
            table[name] = {
                "ate_m": error_stats(result.ate_errors[pose_bin == b]),
                "are_deg": error_stats(result.are_errors[pose_bin == b]),
                "rte_m": error_stats(result.rte_errors[pair_bin == b]),
                "rre_deg": error_stats(result.rre_errors[pair_bin == b]),
            }
        out[kind] = table
    return out


def pose_speeds(result: EvalResult, gt: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Translation (m/s) and rotation (deg/s) ground-truth speed at each associated pose (for plots)."""
    t_gt, v_gt, w_gt = ground_truth_speeds(gt)
    t_q = result.timestamps_s + result.config.time_offset_s
    return np.interp(t_q, t_gt, v_gt), np.interp(t_q, t_gt, w_gt)

