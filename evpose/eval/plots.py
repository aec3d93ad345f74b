"""PNG plots of an evaluation: trajectory views, error over time, error against speed.

matplotlib with the non-interactive Agg backend (no display needed); each figure
is written atomically. Units in labels: millimetres and degrees, as the paper reports.
"""

from __future__ import annotations

from pathlib import Path

from evpose.core.trajectory import Trajectory
from evpose.eval.metrics import EvalResult
from evpose.eval.speed_bins import pose_speeds
from evpose.io.atomic import atomic_path

PLOT_FILES = ("trajectory_top.png", "trajectory_side.png", "error_over_time.png", "error_vs_speed.png")


def _save(fig, path: Path, inputs: tuple = ()) -> None:
    with atomic_path(path, inputs=inputs) as tmp:
        # savefig picks the format from the suffix; the temp name ends in .png too.
        fig.savefig(tmp, dpi=110, format="png")


def _trajectory_view(plt, result: EvalResult, axes: tuple[int, int], title: str):
    names = "xyz"
    fig, ax = plt.subplots(figsize=(6, 5))
    a, b = axes
    ax.plot(result.ref_positions[:, a], result.ref_positions[:, b], "-", color="0.3", lw=1.5, label="ground truth")
    ax.plot(result.est_positions[:, a], result.est_positions[:, b], "-", color="tab:orange", lw=1.0, label="estimate")
    ax.set_xlabel(f"{names[a]} [m]")
    ax.set_ylabel(f"{names[b]} [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(title)
    ax.legend(loc="best")
    fig.tight_layout()
    return fig


def write_plots(result: EvalResult, gt: Trajectory, out_dir: str | Path, inputs: tuple = ()) -> list[Path]:
    """Write the four PNGs into ``out_dir``; returns their paths. ``inputs`` are never overwritten."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    paths = [out_dir / name for name in PLOT_FILES]
    align = result.config.align.value
    figs = [
        _trajectory_view(plt, result, (0, 1), f"top view (x-y), alignment {align}"),
        _trajectory_view(plt, result, (0, 2), f"side view (x-z), alignment {align}"),
    ]

    t = result.timestamps_s - result.timestamps_s[0]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    ax1.plot(t, result.ate_errors * 1e3, lw=1.0, label="ATE")
    if result.rpe_index.size:
        ax1.plot(t[result.rpe_index], result.rte_errors * 1e3, lw=0.8, label="RTE")
    ax1.set_ylabel("translation error [mm]")
    ax1.legend(loc="upper right")
    ax2.plot(t, result.are_errors, lw=1.0, color="tab:red", label="ARE")
    if result.rpe_index.size:
        ax2.plot(t[result.rpe_index], result.rre_errors, lw=0.8, color="tab:purple", label="RRE")
    ax2.set_ylabel("rotation error [deg]")
    ax2.set_xlabel("time [s]")
    ax2.legend(loc="upper right")
    fig.tight_layout()
    figs.append(fig)

    v, w = pose_speeds(result, gt)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 4))
    ax1.scatter(v, result.ate_errors * 1e3, s=4)
    ax1.set_xlabel("translation speed [m/s]")
    ax1.set_ylabel("ATE [mm]")
    ax2.scatter(w, result.are_errors, s=4, color="tab:red")
    ax2.set_xlabel("rotation speed [deg/s]")
    ax2.set_ylabel("ARE [deg]")
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    figs.append(fig)

    for fig, path in zip(figs, paths):
        _save(fig, path, inputs)
        plt.close(fig)
    return paths
