"""``evpose eval EST GT``: ATE / ARE / RTE / RRE of a trajectory, per speed bin, with optional JSON and plots.

``--atlas``: the event-SLAM paper's metrics over the maps of an atlas (``EST.map<k>.txt``).
"""

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


def _drift(percent: float | None) -> str:
    """Scale drift over a map's 0.5 s segments; '-' when the map is too short to have two segments."""
    return f"{'-':>9}" if percent is None else f"{percent:9.1f}"


def format_atlas(summary: dict) -> str:
    """The event-SLAM paper's figures (Table I) and one line per map."""
    lines = [
        f"maps {summary['maps']}, scale {'corrected (sim3)' if summary['correct_scale'] else 'not corrected (se3)'}",
        f"RPE trans [m/m]    {summary['rpe_trans_per_m']:.5f}",
        f"RPE rot [deg/m]    {summary['rpe_rot_deg_per_m']:.5f}",
        f"tracked time [s]   {summary['tracked_time_s']:.3f} of {summary['duration_s']:.3f} ({100 * summary['tracked_fraction']:.1f} %)",
        f"distance [m]       {summary['distance_m']:.3f}",
        f"stability [m s]    {summary['stability_m_s']:.4f}",
        f"ATE [% of dist.]   {summary['ate_percent']:.3f} (worst map {summary['ate_percent_max']:.3f})",
        f"{'map':4} {'poses':>6} {'time [s]':>9} {'dist [m]':>9} {'scale':>8} {'ATE [mm]':>9} {'RPE t [mm]':>10} {'RPE r [deg]':>11} {'drift [%]':>9}",
    ]
    for k, m in enumerate(summary["per_map"]):
        lines.append(f"{k:<4} {m['poses']:>6} {m['tracked_time_s']:9.3f} {m['distance_m']:9.3f} {m['scale']:8.4f} {m['ate_m'] * 1e3:9.3f} {m['rpe_trans_m'] * 1e3:10.3f} {m['rpe_rot_deg']:11.4f} {_drift(m.get('scale_drift_percent'))}")
    return "\n".join(lines)


def evaluate_atlas(estimate: Path, ground_truth: Path, maps: tuple[Path, ...], correct_scale: bool, duration_s: float | None) -> dict:
    """Eqs. (9)-(10) of the event-SLAM paper over ``maps`` (default: the ``EST.map<k>`` files next to ESTIMATE)."""
    from evpose.errors import InputError
    from evpose.eval.inputs import atlas_duration_s, atlas_paths, load_estimate, load_ground_truth
    from evpose.eval.slam_metrics import atlas_metrics

    paths = list(maps) or atlas_paths(estimate)
    trajs = [load_estimate(p) for p in paths]
    gt = load_ground_truth(ground_truth)
    if duration_s is None:
        duration_s = atlas_duration_s(estimate)
    result = atlas_metrics(trajs, gt, correct_scale=correct_scale, duration_s=duration_s)
    if not result.maps:
        raise InputError(paths[0], f"none of the {len(paths)} map trajectories has 3 poses inside the ground truth's time span that can be aligned")
    return {"estimate": str(estimate), "ground_truth": str(ground_truth), "map_files": [str(p) for p in paths], "correct_scale": correct_scale,
            "duration_s": result.duration_s, **result.to_dict()}


def check_numbers(max_time_diff_s: float, time_offset_s: float, rpe_delta: float, duration_s: float | None, rpe_delta_unit: str = "frames") -> None:
    """A NaN or zero RPE delta ended in a ZeroDivisionError/ValueError traceback (so did 0.5 frames; 2.7 frames was
    silently taken as 2); a negative duration was accepted."""
    import math

    from evpose.errors import InputError

    checks = [("--max-time-diff-s", max_time_diff_s, 0.0, True), ("--time-offset-s", time_offset_s, None, True),
              ("--rpe-delta", rpe_delta, 0.0, False), ("--duration-s", duration_s, 0.0, False)]
    for flag, value, low, inclusive in checks:
        if value is None:
            continue
        if not math.isfinite(value) or (low is not None and (value < low or (value == low and not inclusive))):
            bound = "" if low is None else f" {'>=' if inclusive else '>'} {low:g}"
            raise InputError(None, f"{flag} must be a finite number{bound}, got {value}")
    if rpe_delta_unit == "frames" and rpe_delta != int(rpe_delta):
        raise InputError(None, f"--rpe-delta in frames must be a whole number of poses (1 = consecutive), got {rpe_delta:g}")


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
    atlas: bool = False,
    maps: tuple[Path, ...] = (),
    correct_scale: bool = False,
    duration_s: float | None = None,
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
        atlas: SLAM atlas mode: the event-SLAM paper's metrics (RPE per metre averaged over maps, stability = distance x tracked time, tracked fraction, ATE %) over the maps ``EST.map<k>.txt`` next to ESTIMATE (or ESTIMATE alone if there are none).
        maps: Atlas mode with these map trajectories (TUM) instead of the ``EST.map<k>.txt`` files.
        correct_scale: Atlas mode: align each map with scale (sim3), as for event-only runs; --align sim3 implies it.
        duration_s: Atlas mode: span of the recording for the tracked fraction, s (default: from ``EST.slam.json``, else the ground truth's span).
    """
    from evpose.io.atomic import atomic_path, check_outputs, output_set

    check_outputs((json,), inputs=(estimate, ground_truth, *maps), folders=(plots,))
    check_numbers(max_time_diff_s, time_offset_s, rpe_delta, duration_s, rpe_delta_unit)
    if atlas or maps:
        summary = evaluate_atlas(estimate, ground_truth, maps, correct_scale or align == "sim3", duration_s)
        if not quiet:
            print(format_atlas(summary))
        if json is not None:
            with atomic_path(json, inputs=(estimate, ground_truth, *map(Path, summary["map_files"]))) as tmp:
                tmp.write_text(jsonlib.dumps(summary, indent=2) + "\n")
        return 0

    from evpose.eval.inputs import load_estimate, load_ground_truth
    from evpose.eval.metrics import evaluate
    from evpose.eval.speed_bins import speed_bins

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
    with output_set():  # the JSON and the plots of one evaluation appear together
        if json is not None:
            with atomic_path(json, inputs=inputs) as tmp:
                tmp.write_text(jsonlib.dumps(summary, indent=2) + "\n")
        if plots is not None:
            from evpose.eval.plots import write_plots

            write_plots(result, gt, plots, inputs=inputs)
    return 0
