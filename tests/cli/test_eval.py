"""``evpose eval``: agreement with evo's CLI, JSON, speed bins, plots, ground truth from a recording, bad input."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.cli.main import run
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory
from evpose.io.h5 import write_recording_h5
from evpose.io.tum import write_tum


def curved(n: int = 300, dt_us: int = 10_000) -> Trajectory:
    s = np.arange(n) / n
    pos = np.column_stack([np.cos(4 * s), np.sin(3 * s), 0.5 * s])
    rot = Rotation.from_euler("zyx", np.column_stack([2 * s, 0.3 * np.sin(5 * s), 0.2 * s]))
    return Trajectory.from_arrays(1_000_000 + np.arange(n) * dt_us, pos, rot.as_quat())


def perturbed(gt: Trajectory, seed: int) -> Trajectory:
    rng = np.random.default_rng(seed)
    rot = Rotation.from_rotvec(rng.normal(0, 0.01, (len(gt), 3))) * gt.rotation
    return Trajectory.from_arrays(gt.t, gt.position + rng.normal(0, 0.01, gt.position.shape), rot.as_quat())


@pytest.fixture()
def files(tmp_path):
    gt = curved()
    est = perturbed(gt, 0)[3:-3]
    write_tum(tmp_path / "gt.txt", gt)
    write_tum(tmp_path / "est.txt", est)
    return tmp_path / "est.txt", tmp_path / "gt.txt"


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_eval_json_equals_evo_ape_and_evo_rpe_on_the_same_files(tmp_path, files):
    from evo.tools import file_interface

    est, gt = files
    assert run(["eval", str(est), str(gt), "--align", "se3", "--json", str(tmp_path / "out.json"), "--quiet"]) == 0
    ours = json.loads((tmp_path / "out.json").read_text())
    for key, tool, flags in [("ate_m", "evo_ape", ["-r", "trans_part"]), ("rre_deg", "evo_rpe", ["-r", "angle_deg", "-d", "1", "-u", "f"])]:
        subprocess.run([tool, "tum", str(gt), str(est), "-a", *flags, "--save_results", str(tmp_path / f"{key}.zip"), "--no_warnings", "--silent"], check=True)
        theirs = file_interface.load_res_file(str(tmp_path / f"{key}.zip")).stats
        for stat in ("mean", "median", "rmse", "max"):
            assert abs(ours[key][stat] - theirs[stat]) <= 1e-9


def test_eval_prints_table_and_writes_four_pngs(tmp_path, files, capsys):
    est, gt = files
    assert run(["eval", str(est), str(gt), "--plots", str(tmp_path / "plots")]) == 0
    out = capsys.readouterr().out
    assert "ATE [mm]" in out and "RRE [deg]" in out and "294 associated poses" in out and "moderate 2-4 m/s" in out
    for name in ("trajectory_top.png", "trajectory_side.png", "error_over_time.png", "error_vs_speed.png"):
        data = (tmp_path / "plots" / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000


def test_speed_bins_separate_errors_of_slow_and_fast_motion(tmp_path):
    # 1 m/s for the first second, 5 m/s for the next; the estimate is 10 cm off only while fast.
    t = np.arange(0, 2_000_001, 10_000)
    x = np.where(t <= 1_000_000, t / 1e6, 1.0 + 5.0 * (t - 1_000_000) / 1e6)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))
    gt = Trajectory.from_arrays(t, np.column_stack([x, 0 * x, 0 * x]), q)
    off = np.where(t > 1_000_000, 0.1, 0.0)
    est = Trajectory.from_arrays(t, np.column_stack([x, off, 0 * x]), q)
    write_tum(tmp_path / "gt.txt", gt)
    write_tum(tmp_path / "est.txt", est)
    assert run(["eval", str(tmp_path / "est.txt"), str(tmp_path / "gt.txt"), "--align", "none", "--json", str(tmp_path / "o.json"), "--quiet"]) == 0
    bins = json.loads((tmp_path / "o.json").read_text())["speed_bins"]["translation"]
    assert bins["slow"]["ate_m"]["max"] == 0.0
    assert bins["fast"]["ate_m"]["mean"] == pytest.approx(0.1, abs=1e-12)
    assert bins["moderate"]["ate_m"]["n"] <= 1  # only the pose at the switch (3 m/s central difference)
    assert bins["slow"]["ate_m"]["n"] + bins["moderate"]["ate_m"]["n"] + bins["fast"]["ate_m"]["n"] == t.size


def test_ground_truth_can_come_from_a_recording(tmp_path, files):
    est, gt_file = files
    from evpose.io.tum import read_tum

    events = EventArray.from_arrays([1_000_000, 1_000_010], [1, 2], [1, 2], [1, 0])
    write_recording_h5(tmp_path / "rec.h5", Recording(events, ground_truth=read_tum(gt_file), metadata={"width": 10, "height": 10}))
    assert run(["eval", str(est), str(tmp_path / "rec.h5"), "--json", str(tmp_path / "a.json"), "--quiet"]) == 0
    assert run(["eval", str(est), str(gt_file), "--json", str(tmp_path / "b.json"), "--quiet"]) == 0
    a, b = (json.loads((tmp_path / n).read_text()) for n in ("a.json", "b.json"))
    assert a["ate_m"] == b["ate_m"] and a["rre_deg"] == b["rre_deg"]


def test_recording_without_ground_truth_is_a_one_line_error(tmp_path, files, capsys):
    est, _ = files
    events = EventArray.from_arrays([1_000_000, 1_000_010], [1, 2], [1, 2], [1, 0])
    write_recording_h5(tmp_path / "nogt.h5", Recording(events, metadata={"width": 10, "height": 10}))
    assert run(["eval", str(est), str(tmp_path / "nogt.h5")]) == 2
    assert "has no ground truth" in one_line_error(capsys)


def test_malformed_tum_line_is_a_one_line_error_naming_the_line(tmp_path, files, capsys):
    _, gt = files
    bad = tmp_path / "bad.txt"
    bad.write_text("1.0 0 0 0 0 0 0 1\n1.01 0 0 zero 0 0 0 1\n")
    assert run(["eval", str(bad), str(gt)]) == 2
    msg = one_line_error(capsys)
    assert "bad.txt" in msg and "line 2" in msg


def test_non_overlapping_and_too_short_trajectories_are_errors(tmp_path, files, capsys):
    _, gt = files
    late = curved(n=20)
    write_tum(tmp_path / "late.txt", Trajectory.from_arrays(late.t + 100_000_000, late.position, late.quat_xyzw))
    assert run(["eval", str(tmp_path / "late.txt"), str(gt)]) == 2
    assert "does not overlap in time" in one_line_error(capsys)
    write_tum(tmp_path / "short.txt", curved()[5:7])
    assert run(["eval", str(tmp_path / "short.txt"), str(gt)]) == 2
    assert "only 2 poses associate" in one_line_error(capsys)


def test_eval_refuses_to_overwrite_an_input(files, capsys):
    est, gt = files
    before = Path(gt).read_bytes()
    assert run(["eval", str(est), str(gt), "--json", str(gt), "--quiet"]) == 2
    assert "overwrite" in one_line_error(capsys)
    assert Path(gt).read_bytes() == before


def similarity(traj: Trajectory, scale: float, yaw: float, shift) -> Trajectory:
    """``traj`` seen in another world frame with another unit of length (an event-only SLAM map)."""
    r = Rotation.from_euler("z", yaw)
    return Trajectory.from_arrays(traj.t, scale * r.apply(traj.position) + np.asarray(shift), (r * traj.rotation).as_quat())


@pytest.fixture()
def atlas_files(tmp_path):
    gt = curved()
    est = perturbed(gt, 1)
    maps = [similarity(est[10:120], 2.5, 0.7, [1, 2, 3]), similarity(est[150:290], 0.4, -1.2, [0, 0, 5])]
    write_tum(tmp_path / "gt.txt", gt)
    write_tum(tmp_path / "est.txt", maps[1])  # evpose slam writes the longest map as EST too: must not count twice
    for k, m in enumerate(maps):
        write_tum(tmp_path / f"est.map{k}.txt", m)
    return tmp_path / "est.txt", tmp_path / "gt.txt", gt, maps


def test_atlas_mode_finds_the_map_files_and_computes_the_slam_papers_metrics(tmp_path, atlas_files, capsys):
    est, gt_file, gt, maps = atlas_files
    assert run(["eval", str(est), str(gt_file), "--atlas", "--correct-scale", "--json", str(tmp_path / "a.json")]) == 0
    out = capsys.readouterr().out
    assert "RPE trans [m/m]" in out and "stability [m s]" in out and "maps 2" in out
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["map_files"] == [str(tmp_path / "est.map0.txt"), str(tmp_path / "est.map1.txt")]
    assert [m["poses"] for m in doc["per_map"]] == [110, 140]
    # Sim(3) alignment undoes each map's own scale; the residual is the 1 cm perturbation.
    assert [m["scale"] for m in doc["per_map"]] == pytest.approx([1 / 2.5, 1 / 0.4], rel=0.02)
    assert all(m["ate_m"] < 0.03 for m in doc["per_map"])
    tracked = (109 + 139) * 0.01
    dist = sum(float(np.sum(np.linalg.norm(np.diff(gt.position[a:b], axis=0), axis=1))) for a, b in ((10, 120), (150, 290)))
    assert doc["tracked_time_s"] == pytest.approx(tracked, abs=1e-9)
    assert doc["distance_m"] == pytest.approx(dist, rel=1e-9)
    assert doc["stability_m_s"] == pytest.approx(tracked * dist, rel=1e-9)
    assert doc["tracked_fraction"] == pytest.approx(tracked / 2.99, rel=1e-9)  # default duration: the ground truth's span
    expected_rpe = np.mean([m["rpe_trans_m"] / m["distance_m"] for m in doc["per_map"]])
    assert doc["rpe_trans_per_m"] == pytest.approx(expected_rpe, rel=1e-12)


def test_atlas_without_scale_correction_shows_the_scale_error(tmp_path, atlas_files):
    est, gt_file, _, _ = atlas_files
    assert run(["eval", str(est), str(gt_file), "--atlas", "--json", str(tmp_path / "se3.json"), "--quiet"]) == 0
    assert run(["eval", str(est), str(gt_file), "--atlas", "--align", "sim3", "--json", str(tmp_path / "sim3.json"), "--quiet"]) == 0
    se3, sim3 = (json.loads((tmp_path / n).read_text()) for n in ("se3.json", "sim3.json"))
    assert [m["scale"] for m in se3["per_map"]] == [1.0, 1.0] and sim3["correct_scale"] and not se3["correct_scale"]
    assert se3["ate_percent"] > 10 * sim3["ate_percent"]
    assert se3["stability_m_s"] == sim3["stability_m_s"]  # ground-truth distance: independent of the alignment


def test_atlas_maps_option_and_duration_from_the_slam_summary(tmp_path, atlas_files):
    est, gt_file, _, _ = atlas_files
    est.with_suffix(".slam.json").write_text(json.dumps({"duration_s": 5.0}))
    assert run(["eval", str(est), str(gt_file), "--maps", str(tmp_path / "est.map1.txt"), "--correct-scale", "--json", str(tmp_path / "m.json"), "--quiet"]) == 0
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc["maps"] == 1 and doc["duration_s"] == 5.0 and doc["tracked_fraction"] == pytest.approx(1.39 / 5.0)
    assert run(["eval", str(est), str(gt_file), "--atlas", "--duration-s", "10", "--json", str(tmp_path / "d.json"), "--quiet"]) == 0
    assert json.loads((tmp_path / "d.json").read_text())["duration_s"] == 10.0


def test_a_slam_summary_with_an_infinite_duration_is_ignored(tmp_path):
    from evpose.eval.inputs import atlas_duration_s

    est = tmp_path / "est.txt"
    est.with_suffix(".slam.json").write_text(json.dumps({"duration_s": float("inf")}))
    assert atlas_duration_s(est) is None
    est.with_suffix(".slam.json").write_text(json.dumps({"duration_s": 2.5}))
    assert atlas_duration_s(est) == 2.5


def test_atlas_without_usable_maps_is_a_one_line_error(tmp_path, files, capsys):
    _, gt = files
    late = curved(n=20)
    write_tum(tmp_path / "late.txt", Trajectory.from_arrays(late.t + 100_000_000, late.position, late.quat_xyzw))
    assert run(["eval", str(tmp_path / "late.txt"), str(gt), "--atlas"]) == 2
    assert "none of the 1 map trajectories" in one_line_error(capsys)


def test_plots_folder_that_is_a_file_is_a_one_line_error_before_evaluating(tmp_path, files, capsys):
    # Used to end in a NotADirectoryError traceback from the first PNG's temporary file.
    est, gt = files
    in_the_way = tmp_path / "plots"
    in_the_way.write_text("not a folder")
    assert run(["eval", str(est), str(gt), "--quiet", "--plots", str(in_the_way)]) == 2
    assert "plots: output folder exists and is a file" in one_line_error(capsys)
    assert in_the_way.read_text() == "not a folder"


@pytest.mark.parametrize("args, message", [
    (["--rpe-delta", "0"], "--rpe-delta must be a finite number > 0, got 0.0"),
    (["--rpe-delta", "nan"], "--rpe-delta must be a finite number > 0, got nan"),
    (["--max-time-diff-s", "-1"], "--max-time-diff-s must be a finite number >= 0"),
    (["--time-offset-s", "inf"], "--time-offset-s must be a finite number, got inf"),
    (["--atlas", "--duration-s", "-2"], "--duration-s must be a finite number > 0"),
])
def test_non_finite_or_out_of_range_numbers_are_one_line_errors(files, capsys, args, message):
    # --rpe-delta 0 was a ZeroDivisionError traceback, nan a ValueError one; a negative --duration-s was used as is.
    est, gt = files
    assert run(["eval", str(est), str(gt), "--quiet", *args]) == 2
    assert message in one_line_error(capsys)


@pytest.mark.parametrize("delta", ["0.5", "2.7"])
def test_fractional_rpe_delta_in_frames_is_a_one_line_error(files, capsys, delta):
    # 0.5 frames was a ZeroDivisionError traceback from evo, 2.7 frames silently became 2.
    est, gt = files
    assert run(["eval", str(est), str(gt), "--quiet", "--rpe-delta", delta]) == 2
    assert one_line_error(capsys).endswith(f"--rpe-delta in frames must be a whole number of poses (1 = consecutive), got {delta}")


def test_fractional_rpe_delta_in_metres_is_accepted(files, capsys):
    est, gt = files
    assert run(["eval", str(est), str(gt), "--quiet", "--rpe-delta", "0.5", "--rpe-delta-unit", "meters"]) == 0


def test_eval_interrupted_while_plotting_writes_neither_the_json_nor_any_plot(tmp_path, files, monkeypatch, capsys):
    import evpose.eval.plots as plots

    est, gt = files
    real = plots._save
    saved = []

    def interrupted_after_two(fig, path, inputs):
        if len(saved) == 2:
            raise KeyboardInterrupt
        saved.append(path)
        real(fig, path, inputs)

    monkeypatch.setattr(plots, "_save", interrupted_after_two)
    out = tmp_path / "out"
    code = run(["eval", str(est), str(gt), "--json", str(out / "e.json"), "--plots", str(out / "plots"), "--quiet"])
    assert code == 130 and len(saved) == 2
    assert [p for p in out.rglob("*") if p.is_file()] == []  # the folders made for them may stay, empty
