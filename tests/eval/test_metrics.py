"""ATE/ARE/RTE/RRE on trajectories with known answers, error cases, and agreement with the evo CLIs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError
from evpose.eval.metrics import Alignment, DeltaUnit, EvalConfig, evaluate


def helix(n: int = 300, dt_us: int = 10_000, t0_us: int = 1_000_000) -> Trajectory:
    """A curved, non-planar path with changing orientation (Umeyama well-posed)."""
    i = np.arange(n)
    t = t0_us + i * dt_us
    s = i / n
    pos = np.column_stack([np.cos(4 * s), np.sin(3 * s), 0.5 * s + 0.1 * np.sin(9 * s)])
    rot = Rotation.from_euler("zyx", np.column_stack([2 * s, 0.3 * np.sin(5 * s), 0.2 * s]))
    return Trajectory.from_arrays(t, pos, rot.as_quat())


def noisy(gt: Trajectory, seed: int, pos_sigma: float = 0.01, rot_sigma: float = 0.01) -> Trajectory:
    rng = np.random.default_rng(seed)
    pos = gt.position + rng.normal(0, pos_sigma, gt.position.shape)
    rot = Rotation.from_rotvec(rng.normal(0, rot_sigma, (len(gt), 3))) * gt.rotation
    return Trajectory.from_arrays(gt.t, pos, rot.as_quat())


def test_pure_offset_gives_offset_norm_without_alignment_and_zero_with_se3():
    gt = helix()
    est = Trajectory.from_arrays(gt.t, gt.position + [0.1, -0.2, 0.3], gt.quat_xyzw)
    raw = evaluate(est, gt, EvalConfig(align=Alignment.NONE))
    assert raw.ate["mean"] == pytest.approx(np.sqrt(0.14), abs=1e-12)
    assert raw.ate["max"] == pytest.approx(np.sqrt(0.14), abs=1e-12)
    assert raw.are["max"] < 1e-6
    assert raw.rte["max"] < 1e-12  # a constant offset does not change relative motion
    aligned = evaluate(est, gt, EvalConfig(align=Alignment.SE3))
    assert aligned.ate["max"] < 1e-9
    np.testing.assert_allclose(aligned.alignment[:3, 3], [-0.1, 0.2, -0.3], atol=1e-9)


def test_pure_world_rotation_gives_its_angle_as_are_and_no_relative_error():
    gt = helix()
    R0 = Rotation.from_euler("z", 10, degrees=True)
    est = Trajectory.from_arrays(gt.t, R0.apply(gt.position), (R0 * gt.rotation).as_quat())
    raw = evaluate(est, gt, EvalConfig(align=Alignment.NONE))
    # inv(R_gt) R0 R_gt is a conjugate of R0: the same 10 degree angle at every pose.
    assert raw.are["min"] == pytest.approx(10.0, abs=1e-9)
    assert raw.are["max"] == pytest.approx(10.0, abs=1e-9)
    assert raw.rre["max"] < 1e-6 and raw.rte["max"] < 1e-12
    aligned = evaluate(est, gt, EvalConfig(align=Alignment.SE3))
    assert aligned.are["max"] < 1e-6 and aligned.ate["max"] < 1e-9


def test_scaled_trajectory_is_recovered_by_sim3_only():
    gt = helix()
    est = Trajectory.from_arrays(gt.t, 2.0 * gt.position, gt.quat_xyzw)
    sim3 = evaluate(est, gt, EvalConfig(align=Alignment.SIM3))
    assert sim3.scale == pytest.approx(0.5, abs=1e-12)
    assert sim3.ate["max"] < 1e-9
    se3 = evaluate(est, gt, EvalConfig(align=Alignment.SE3))
    assert se3.ate["mean"] > 0.1


def test_rpe_delta_in_frames_sets_the_pair_count():
    gt = helix(n=100)
    est = noisy(gt, 1)
    one = evaluate(est, gt, EvalConfig(rpe_delta=1))
    ten = evaluate(est, gt, EvalConfig(rpe_delta=10, rpe_delta_unit=DeltaUnit.FRAMES))
    ten_all = evaluate(est, gt, EvalConfig(rpe_delta=10, rpe_all_pairs=True))
    # evo's default pairs are disjoint (0-10, 10-20, ...); all_pairs overlaps them (0-10, 1-11, ...).
    assert one.rte["n"] == 99 and ten.rte["n"] == 9 and ten_all.rte["n"] == 90
    assert one.rpe_index[0] == 1 and ten.rpe_index[1] == 20 and ten_all.rpe_index[1] == 11


def test_association_keeps_only_poses_within_max_time_diff():
    gt = helix(n=100)
    est = noisy(gt, 2)[::3]
    shifted = Trajectory.from_arrays(est.t + 3000, est.position, est.quat_xyzw)  # 3 ms late
    res = evaluate(shifted, gt, EvalConfig(max_time_diff_s=0.004))
    assert res.n_associated == len(est)
    with pytest.raises(InputError, match="associate"):
        evaluate(shifted, gt, EvalConfig(max_time_diff_s=0.002))


def test_trajectories_without_time_overlap_are_an_input_error():
    gt = helix(n=50)
    late = Trajectory.from_arrays(gt.t + 10_000_000, gt.position, gt.quat_xyzw)
    with pytest.raises(InputError, match="does not overlap in time"):
        evaluate(late, gt, est_name="est.txt")


def test_too_few_associated_poses_is_an_input_error():
    gt = helix(n=50)
    with pytest.raises(InputError, match="only 2 poses associate"):
        evaluate(gt[10:12], gt, est_name="est.txt")


# --- agreement with the evo command-line tools -------------------------------------------


def write_tum_text(path: Path, traj: Trajectory) -> None:
    with open(path, "w") as fh:
        for t, p, q in zip(traj.t, traj.position, traj.quat_xyzw):
            fh.write(f"{t // 1_000_000}.{t % 1_000_000:06d} " + " ".join(repr(float(v)) for v in (*p, *q)) + "\n")


def evo_stats(tool: str, gt: Path, est: Path, out: Path, *flags: str) -> dict:
    """Run evo's command-line entry point (``evo_ape``/``evo_rpe``) in this process and read its saved results.

    In-process saves an interpreter start per call; tests/cli/test_eval.py runs the real executables.
    """
    from unittest import mock

    from evo.cli import entry_points
    from evo.tools import file_interface

    argv = [tool, "tum", str(gt), str(est), *flags, "--save_results", str(out), "--no_warnings", "--silent"]
    with mock.patch("sys.argv", argv):
        {"evo_ape": entry_points.ape, "evo_rpe": entry_points.rpe}[tool]()
    return file_interface.load_res_file(str(out)).stats


@pytest.mark.parametrize(
    "align,offset_us,flags",
    [(Alignment.SE3, 0, ["-a"]), (Alignment.SIM3, 0, ["-a", "-s"]), (Alignment.NONE, 2000, ["--t_offset", "0.002"])],
)
def test_metrics_equal_evo_ape_and_evo_rpe(tmp_path, align, offset_us, flags):
    gt = helix(n=400)
    est = noisy(gt, 3, pos_sigma=0.02, rot_sigma=0.02)[5:-7:2]
    est = Trajectory.from_arrays(est.t - offset_us, est.position, est.quat_xyzw)  # the estimate's clock lags
    gt_file, est_file = tmp_path / "gt.txt", tmp_path / "est.txt"
    write_tum_text(gt_file, gt)
    write_tum_text(est_file, est)
    res = evaluate(est, gt, EvalConfig(align=align, rpe_delta=3, time_offset_s=offset_us / 1e6))
    assert res.n_associated == len(est)
    checks = [
        ("evo_ape", res.ate, ["-r", "trans_part"]),
        ("evo_ape", res.are, ["-r", "angle_deg"]),
        ("evo_rpe", res.rte, ["-r", "trans_part", "-d", "3", "-u", "f"]),
        ("evo_rpe", res.rre, ["-r", "angle_deg", "-d", "3", "-u", "f"]),
    ]
    for k, (tool, ours, extra) in enumerate(checks):
        theirs = evo_stats(tool, gt_file, est_file, tmp_path / f"r{k}.zip", *flags, *extra)
        for stat in ("mean", "median", "rmse", "max", "min", "std"):
            assert abs(ours[stat] - theirs[stat]) <= 1e-9, (tool, extra, stat, ours[stat], theirs[stat])


def test_empty_estimate_is_an_input_error():
    gt = helix(n=20)
    with pytest.raises(InputError, match="no poses"):
        evaluate(Trajectory.empty(), gt, est_name="est.txt")


def test_a_ground_truth_too_short_to_evaluate_is_named_not_the_estimate():
    gt = helix(n=50)
    with pytest.raises(InputError, match=r"^gt.txt: the ground truth has only 1 pose \(need at least 3\)"):
        evaluate(gt, gt[10:11], est_name="est.txt", ref_name="gt.txt")
