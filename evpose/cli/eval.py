"""``evpose eval EST GT``: ATE / ARE / RTE / RRE of a trajectory, per speed bin, with optional JSON and plots."""

from __future__ import annotations

import json as jsonlib
from pathlib import Path
from typing import Literal

import tyro

from evpose.eval.metrics import Alignment, DeltaUnit, EvalConfig


def format_table(summary: dict) -> str:
    """The four metrics as a small fixed-width table (mm and degrees, as the paper reports)."""
    rows = [("ATE [mm]", summary["ate_m"], 1e3), ("ARE [deg]", summary["are_deg"], 1.0), ("RTE [mm]", summary["rte_m"], 1e3), ("RRE [deg]", summary["rre_deg"], 1.0)]
    lines = [f"{'':10} {'mean':>10} {'median':>10} {'rmse':>10} {'max':>10} {'n':>7}"]
    for name, stats, k in rows:
        if not stats.get("n"):
            lines.append(f"{name:10} {'-':>10} {'-':>10} {'-':>10} {'-':>10} {0:>7}")
            continue
        lines.append(f"{name:10} {stats['mean'] * k:10.4f} {stats['median'] * k:10.4f} {stats['rmse'] * k:10.4f} {stats['max'] * k:10.4f} {stats['n']:>7}")
    return "\n".join(lines)


def format_speed_bins(bins: dict) -> str:
    """Mean ATE/RTE per translation-speed bin and ARE/RRE per rotation-speed bin, with pose counts."""
    te, re_ = bins["edges"]["translation_m_s"], bins["edges"]["rotation_deg_s"]
    lines = [f"{'speed bin':32} {'ATE [mm]':>14} {'RTE [mm]':>14} {'ARE [deg]':>14} {'RRE [deg]':>14}"]
    labels = {"slow": (f"< {te[0]:g} m/s", f"< {re_[0]:g} deg/s"), "moderate": (f"{te[0]:g}-{te[1]:g} m/s", f"{re_[0]:g}-{re_[1]:g} deg/s"), "fast": (f"> {te[1]:g} m/s", f"> {re_[1]:g} deg/s")}

    def cell(stats: dict, k: float) -> str:
        return f"{stats['mean'] * k:.4f} ({stats['n']})" if stats.get("n") else "- (0)"

    for name, (tl, rl) in labels.items():
        t, r = bins["translation"][name], bins["rotation"][name]
        lines.append(f"{name + ' ' + tl + ' / ' + rl:32} {cell(t['ate_m'], 1e3):>14} {cell(t['rte_m'], 1e3):>14} {cell(r['are_deg'], 1):>14} {cell(r['rre_deg'], 1):>14}")
    return "\n".join(lines)


def main(
    estimate: tyro.conf.Positional[Path],
    ground_truth: tyro.conf.Positional[Path],
    align: Literal["se3", "sim3", "none"] = "se3",
    json: Path | None = None,
    plots: Path | None = None,
    max_time_diff_s: float = 0.01,
    time_offset_s: float = 0.0,
    rpe_delta: float = 1.0,
    rpe_delta_unit: Literal["frames", "meters", "degrees", "radians"] = "frames",
    rpe_all_pairs: bool = False,
    quiet: bool = False,
) -> int:
    """Compare an estimated trajectory (TUM file) with ground truth (TUM file or any recording with ground truth).

    Association, alignment and metrics are evo's and equal `evo_ape`/`evo_rpe` on
    the same files. RTE/RRE compare pose pairs `rpe_delta` apart (default: consecutive
    poses). Errors are also reported per speed bin (slow/moderate/fast: < 2, 2-4,
    > 4 m/s and < 10, 10-30, > 30 deg/s of ground-truth motion).

    Args:
        estimate: Estimated trajectory, TUM text (t tx ty tz qx qy qz qw, t in seconds).
        ground_truth: Ground-truth TUM file, or a recording (ECD folder, evpose HDF5...) with ground truth.
        align: Alignment of the estimate before measuring: se3, sim3 (with scale) or none.
        json: Write all figures (incl. speed bins) to this JSON file.
        plots: Write PNG plots (top/side views, error over time, error vs speed) into this folder.
        max_time_diff_s: Largest timestamp difference for associating poses, seconds.
        time_offset_s: Offset added to the estimate's timestamps for association, seconds.
        rpe_delta: Spacing of RPE pose pairs in rpe_delta_unit.
        rpe_delta_unit: Unit of rpe_delta.
        rpe_all_pairs: Use every (overlapping) pose pair rpe_delta apart, not consecutive disjoint pairs (evo's --all_pairs).
        quiet: Do not print the table.
    """
    from evpose.eval.inputs import load_estimate, load_ground_truth
    from evpose.eval.metrics import evaluate
    from evpose.eval.speed_bins import speed_bins
    from evpose.io.atomic import atomic_path

    config = EvalConfig(
        align=Alignment(align),
        max_time_diff_s=max_time_diff_s,
        time_offset_s=time_offset_s,
        rpe_delta=rpe_delta,
        rpe_delta_unit=DeltaUnit(rpe_delta_unit),
        rpe_all_pairs=rpe_all_pairs,
    )
    est = load_estimate(estimate)
    gt = load_ground_truth(ground_truth)
    result = evaluate(est, gt, config, est_name=str(estimate), ref_name=str(ground_truth))
    summary = result.summary()
    summary["estimate"] = str(estimate)
    summary["ground_truth"] = str(ground_truth)
    summary["speed_bins"] = speed_bins(result, gt)
    if not quiet:
        print(f"{result.n_associated} associated poses, alignment {config.align.value}, RPE delta {config.rpe_delta:g} {config.rpe_delta_unit.value}")
        print(format_table(summary))
        print()
        print(format_speed_bins(summary["speed_bins"]))
    inputs = (estimate, ground_truth)
    if json is not None:
        with atomic_path(json, inputs=inputs) as tmp:
            tmp.write_text(jsonlib.dumps(summary, indent=2) + "\n")
    if plots is not None:
        from evpose.eval.plots import write_plots

        write_plots(result, gt, plots, inputs=inputs)
    return 0
