"""``evpose track``: TUM output, timings file, and one-line errors for bad input."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tracker"))
from tracker_synthetic import generate  # noqa: E402

from evpose.cli.main import run  # noqa: E402
from evpose.io.h5 import write_recording_h5  # noqa: E402
from evpose.io.map_ply import write_contour_map  # noqa: E402
from evpose.io.tum import read_tum  # noqa: E402


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    rec, cmap, _ = generate(duration_s=0.12, seed=4)
    d = tmp_path_factory.mktemp("track")
    write_recording_h5(d / "rec.h5", rec)
    write_contour_map(d / "map.ply", cmap)
    return d, rec


def test_track_writes_a_tum_trajectory_and_timings(files):
    d, rec = files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(d / "est.txt"), "--mode", "stpe", "--rate-hz", "100",
                "--timings", str(d / "t.json"), "--no-progress"])
    assert code == 0
    est = read_tum(d / "est.txt")
    doc = json.loads((d / "t.json").read_text())
    n = len(doc["updates"])
    assert n >= 7 and len(est) == n and np.all(np.diff(est.t) == 10_000)
    gt = rec.ground_truth.interpolate(est.t)
    assert np.max(np.linalg.norm(est.position - gt.position, axis=1)) < 0.03
    assert "registration" in doc["modules"]
    assert doc["summary_ms"]["total"]["n"] == n and doc["config"]["rate_hz"] == 100.0


def test_track_accepts_an_explicit_initial_pose(files, tmp_path):
    d, rec = files
    T = rec.ground_truth.interpolate(rec.t_start_us)
    pose = " ".join(str(v) for v in np.concatenate([T.position[0], T.quat_xyzw[0]]))
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--init", pose, "--mode", "stpe", "--no-progress"])
    assert code == 0 and len(read_tum(tmp_path / "e.txt")) > 10


@pytest.mark.parametrize(
    "args, message",
    [
        (["--init", "1 2 3"], "--init expects"),
        # A component of 1e300 overflowed the quaternion's norm: scipy's "Found zero norm quaternions" traceback.
        (["--init", "0 0 0 0 0 0 1e300"], "--init quaternion's length is beyond the float range"),
        (["--init", "1e30 0 0 0 0 0 1"], "--init position [1e+30, 0.0, 0.0] is beyond"),
        (["--mode", "warp"], "--mode must be one of"),
        (["--rate-hz", "0"], "--rate-hz must be positive"),
        (["--config", "missing.yaml"], "cannot read the config file"),
    ],
)
def test_track_bad_options_are_one_line_errors(files, tmp_path, capsys, args, message):
    d, _ = files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "e.txt").exists()


def test_track_refuses_to_overwrite_its_input(files, capsys):
    d, _ = files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(d / "map.ply"), "--no-progress"])
    assert code == 2 and "overwrite" in capsys.readouterr().err


def test_track_with_a_map_in_another_frame_fails_with_one_line(files, tmp_path, capsys):
    d, rec = files
    from evpose.io.map_ply import read_contour_map

    cmap = read_contour_map(d / "map.ply")
    import dataclasses

    write_contour_map(tmp_path / "far.ply", dataclasses.replace(cmap, points=cmap.points + 100.0))
    code = run(["track", str(d / "rec.h5"), "--map", str(tmp_path / "far.ply"), "--out", str(tmp_path / "e.txt"), "--mode", "stpe", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "same frame" in err and len(err.splitlines()) == 1
    assert err.split(": ")[2] == str(tmp_path / "far.ply")  # "evpose track: error: MAP: ...": the map is named, it is what is wrong


def bare_ground_map(cmap, n=300):
    """A patch of ``cmap``'s ground with no edge, in view of the start pose: a wrong map, not one in another frame."""
    import dataclasses

    patch = np.c_[np.random.default_rng(0).uniform(-0.04, 0.04, (n, 2)) + [0.0, -0.55], np.zeros(n)]
    return dataclasses.replace(cmap, points=patch, **{k: getattr(cmap, k)[:n] for k in
                                                      ("edge_normal", "plane_normal", "region_id", "curvature", "brightness_sign")})


def test_track_with_a_map_that_never_registers_fails_with_one_line_and_writes_nothing(files, tmp_path, capsys):
    d, rec = files
    from evpose.io.map_ply import read_contour_map

    cmap = read_contour_map(d / "map.ply")
    # In view of the start pose, but on bare ground with no edge: a wrong map, not one in another frame.
    write_contour_map(tmp_path / "wrong.ply", bare_ground_map(cmap))
    out = tmp_path / "e.txt"
    code = run(["track", str(d / "rec.h5"), "--map", str(tmp_path / "wrong.ply"), "--out", str(out), "--mode", "stpe",
                "--acquire-s", "0.05", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "wrong.ply: updates 1-" in err and "no update registered" in err
    assert not out.exists()


def test_track_refuses_a_wrong_map_that_registers_only_by_chance_under_dense_events(tmp_path, capsys):
    # 2e6 noise events/s cover the image densely: a patch of bare ground registers every update, by chance alone.
    rec, cmap, _ = generate(duration_s=0.12, seed=4, noise_rate_hz=2e6)
    write_recording_h5(tmp_path / "rec.h5", rec)
    write_contour_map(tmp_path / "map.ply", cmap)
    write_contour_map(tmp_path / "wrong.ply", bare_ground_map(cmap))
    out = tmp_path / "e.txt"
    code = run(["track", str(tmp_path / "rec.h5"), "--map", str(tmp_path / "wrong.ply"), "--out", str(out), "--mode", "stpe",
                "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "wrong.ply: updates 1-" in err and "than chance" in err
    assert not out.exists()
    # The right map, under the same events, is accepted.
    code = run(["track", str(tmp_path / "rec.h5"), "--map", str(tmp_path / "map.ply"), "--out", str(out), "--mode", "stpe",
                "--no-progress"])
    assert code == 0 and out.exists()


def test_track_in_a_fused_mode_without_imu_is_a_one_line_error(files, tmp_path, capsys):
    d, _ = files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--mode", "full", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "needs IMU data" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "e.txt").exists()


@pytest.fixture(scope="module")
def landing_files(sim_landing_small, tmp_path_factory):
    """0.3 s of the small simulated landing (with IMU) and a map sampled along its true edges."""
    import dataclasses

    from evpose.bench.registration_bias import true_edge_points
    from evpose.core.contour_map import ContourMap

    rec = sim_landing_small.recording
    rec = dataclasses.replace(rec, events=rec.events.time_window(int(rec.events.t[0]), int(rec.events.t[0]) + 300_000))
    d = tmp_path_factory.mktemp("track_full")
    write_recording_h5(d / "rec.h5", rec)
    write_contour_map(d / "map.ply", ContourMap.from_points(true_edge_points(sim_landing_small.edges, step_m=0.02)))
    return d, rec


def test_smoothed_trajectory_is_written_beside_the_real_time_one(landing_files, tmp_path):
    d, rec = landing_files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--mode", "full",
                "--smoothed", str(tmp_path / "s.txt"), "--no-progress"])
    assert code == 0
    online, smooth = read_tum(tmp_path / "e.txt"), read_tum(tmp_path / "s.txt")
    assert len(online) > 20 and np.array_equal(online.t, smooth.t)
    assert not np.array_equal(online.position, smooth.position)  # re-estimated with later registrations
    gt = rec.ground_truth.interpolate(smooth.t)
    assert np.max(np.linalg.norm(smooth.position - gt.position, axis=1)) < 0.05


def test_smoothed_lag_sets_how_many_later_registrations_each_pose_waits_for(landing_files, tmp_path, capsys):
    d, rec = landing_files
    base = ["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--mode", "full", "--no-progress"]
    assert run(base + ["--out", str(tmp_path / "e.txt"), "--smoothed", str(tmp_path / "s8.txt"), "--smoothed-lag", "8"]) == 0
    assert run(base + ["--out", str(tmp_path / "e2.txt"), "--smoothed", str(tmp_path / "s400.txt")]) == 0
    online, s8, s400 = read_tum(tmp_path / "e.txt"), read_tum(tmp_path / "s8.txt"), read_tum(tmp_path / "s400.txt")
    assert np.array_equal(online.t, s8.t) and np.array_equal(online.t, s400.t)
    # The window's corrections reach each pose, but only those of the next 7 registrations, not the whole run's.
    assert not np.array_equal(s8.position, online.position) and not np.array_equal(s8.position, s400.position)
    gt = rec.ground_truth.interpolate(s8.t)
    assert np.max(np.linalg.norm(s8.position - gt.position, axis=1)) < 0.05
    capsys.readouterr()
    code = run(base + ["--out", str(tmp_path / "e3.txt"), "--smoothed", str(tmp_path / "s1.txt"), "--smoothed-lag", "1"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--smoothed-lag must be at least 2" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "e3.txt").exists()
    code = run(base + ["--out", str(tmp_path / "e4.txt"), "--smoothed-lag", "8"])  # nothing to set the lag of
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--smoothed-lag needs --smoothed" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "e4.txt").exists()


def test_smoothed_needs_the_factor_graph(landing_files, tmp_path, capsys):
    d, _ = landing_files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--mode", "stpe",
                "--smoothed", str(tmp_path / "s.txt"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--smoothed needs --mode full" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "s.txt").exists()


def test_track_with_events_ending_before_the_ground_truth_starts_is_a_one_line_error(files, tmp_path, capsys):
    # Used to exit 0 with "0 updates, 0 poses written to e.txt" and write no file.
    d, rec = files
    import dataclasses

    from evpose.core.trajectory import Trajectory

    gt = rec.ground_truth
    late = dataclasses.replace(rec, ground_truth=Trajectory(gt.t + 10_000_000, gt.position, gt.quat_xyzw), source=None)
    write_recording_h5(tmp_path / "late.h5", late)
    out = tmp_path / "e.txt"
    code = run(["track", str(tmp_path / "late.h5"), "--map", str(d / "map.ply"), "--out", str(out), "--mode", "stpe", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "late.h5: no pose update to run" in err
    assert not out.exists()


def test_track_out_onto_a_folder_is_refused_before_tracking(files, tmp_path, capsys):
    # Used to track the whole recording, then fail in os.replace with an IsADirectoryError traceback.
    d, _ = files
    (tmp_path / "est").mkdir()
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "est"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "output is an existing folder" in err


@pytest.mark.parametrize("args, message", [
    (["--rate-hz", "inf"], "rate_hz: expected a finite number, got inf"),
    (["--rate-hz", "5000"], "rate_hz: 5000.0 is outside the allowed range 10.0..1000.0 Hz"),
    (["--acquire-s", "nan"], "--acquire-s must be a finite number"),
    (["--acquire-s", "-1"], "--acquire-s must be a finite number of seconds >= 0"),
])
def test_track_numbers_from_flags_are_checked_like_config_files(files, tmp_path, capsys, args, message):
    # --rate-hz inf ran ~1e6 updates per recorded second (a hang); --acquire-s nan was a ValueError traceback.
    d, _ = files
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and len(err.splitlines()) == 1


def test_track_with_an_imu_on_another_clock_is_a_one_line_error(landing_files, tmp_path, capsys):
    # IMU samples that start after the events: the first preintegration had nothing to integrate, and the error
    # named no file.
    import dataclasses

    d, rec = landing_files
    imu = dataclasses.replace(rec.imu, t=rec.imu.t + 10_000_000)
    write_recording_h5(tmp_path / "late.h5", dataclasses.replace(rec, imu=imu))
    code = run(["track", str(tmp_path / "late.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert str(tmp_path / "late.h5") in err and "imu: the IMU samples" in err and "do not cover" in err
    assert not (tmp_path / "e.txt").exists()


def test_track_with_an_absurd_imu_is_a_one_line_error(landing_files, tmp_path, capsys):
    # Accelerations of 1e30 m/s^2 (wrong units) ended in gtsam's "Indeterminate linear system" traceback.
    import dataclasses

    d, rec = landing_files
    write_recording_h5(tmp_path / "huge.h5", dataclasses.replace(rec, imu=dataclasses.replace(rec.imu, acc=rec.imu.acc * 1e30)))
    code = run(["track", str(tmp_path / "huge.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "IMU sample 0: acceleration" in err and "beyond any IMU's range" in err


def _paused(rec, at_us: int, gap_us: int):
    """``rec`` with every stream from ``at_us`` on moved ``gap_us`` later (a recorder paused that long)."""
    import dataclasses

    from evpose.core.events import EventArray
    from evpose.core.imu import ImuSamples
    from evpose.core.trajectory import Trajectory

    def shift(t):
        return np.where(t >= at_us, t + gap_us, t)
    ev, gt, imu = rec.events, rec.ground_truth, rec.imu
    return dataclasses.replace(rec, events=EventArray(shift(ev.t), ev.x, ev.y, ev.p),
                               ground_truth=Trajectory(shift(gt.t), gt.position, gt.quat_xyzw),
                               imu=None if imu is None else ImuSamples(shift(imu.t), imu.acc, imu.gyro))


def test_track_over_an_hour_long_event_gap_reports_it_once_and_resumes_after_it(landing_files, tmp_path, capsys):
    d, rec = landing_files
    write_recording_h5(tmp_path / "paused.h5", _paused(rec, rec.t_start_us + 150_000, 3_600_000_000))
    code = run(["track", str(tmp_path / "paused.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"),
                "--smoothed", str(tmp_path / "s.txt"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 1 and "lost track in 1 of" in err and "no events or IMU samples for 3600.0" in err
    est, smooth = read_tum(tmp_path / "e.txt"), read_tum(tmp_path / "s.txt")
    after = est.t > 3_600_000_000
    assert after.sum() > 20 and (~after).sum() > 20  # tracked before and after the gap, nothing inside it
    assert np.array_equal(est.t, smooth.t)
    truth = rec.ground_truth.interpolate(np.where(est.t > 3_600_000_000, est.t - 3_600_000_000, est.t))
    for traj in (est, smooth):  # the smoothed stretches are replayed separately: no hour of missing IMU in them
        assert np.max(np.linalg.norm(traj.position - truth.position, axis=1)) < 0.05


def test_track_writes_no_smoothed_pose_where_the_restart_gate_withholds_the_real_time_one(landing_files, tmp_path, capsys):
    d, rec = landing_files
    write_recording_h5(tmp_path / "paused.h5", _paused(rec, rec.t_start_us + 150_000, 3_600_000_000))
    (tmp_path / "gate.yaml").write_text("restart_gate:\n  min_chance_z: 100.0\n")  # never passes here
    g = rec.ground_truth
    init = " ".join(repr(float(v)) for v in (*g.position[0], *g.quat_xyzw[0]))
    code = run(["track", str(tmp_path / "paused.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"),
                "--smoothed", str(tmp_path / "s.txt"), "--init", init, "--config", str(tmp_path / "gate.yaml"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 1, err
    est, smooth = read_tum(tmp_path / "e.txt"), read_tum(tmp_path / "s.txt")
    assert len(est) > 20 and np.array_equal(est.t, smooth.t) and est.t.max() < 3_600_000_000


def test_track_interrupted_between_its_outputs_writes_none_of_them(files, tmp_path, monkeypatch, capsys):
    import evpose.io.tum as tum

    d, _ = files

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(tum, "write_tum", interrupted)  # after the --timings file was written
    code = run(["track", str(d / "rec.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--mode", "stpe",
                "--timings", str(tmp_path / "t.json"), "--no-progress"])
    assert code == 130 and "interrupted" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def _short_gaps(folder):
    """A tracker config whose gap limit (0.1 s) fits the 0.3-1 s test recordings."""
    (folder / "gaps.yaml").write_text("max_event_gap_ms: 100\n")
    return str(folder / "gaps.yaml")


def test_track_in_full_mode_stops_where_the_imu_ends_instead_of_holding_its_last_sample(landing_files, tmp_path, capsys):
    import dataclasses

    d, rec = landing_files
    cut = rec.t_start_us + 150_000
    write_recording_h5(tmp_path / "short_imu.h5", dataclasses.replace(rec, imu=rec.imu[rec.imu.t < cut]))
    code = run(["track", str(tmp_path / "short_imu.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress",
                "--config", _short_gaps(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1 and "the IMU samples end at t=" in err and "--mode stpe needs no IMU" in err
    est = read_tum(tmp_path / "e.txt")
    assert est.t[-1] < cut + 10_000 and len(est) > 20


def test_track_in_full_mode_restarts_after_a_hole_in_the_imu(sim_landing_small, landing_files, tmp_path, capsys):
    import dataclasses

    d, _ = landing_files
    rec = sim_landing_small.recording
    t0 = rec.t_start_us
    hole = (rec.imu.t >= t0 + 300_000) & (rec.imu.t < t0 + 500_000)
    write_recording_h5(tmp_path / "hole.h5", dataclasses.replace(rec, imu=rec.imu[~hole]))
    code = run(["track", str(tmp_path / "hole.h5"), "--map", str(d / "map.ply"), "--out", str(tmp_path / "e.txt"), "--no-progress",
                "--config", _short_gaps(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1 and "lost track in 1 of" in err and "no IMU samples for 0.2" in err
    est = read_tum(tmp_path / "e.txt")
    assert np.sum(est.t > t0 + 500_000) > 50  # tracked again after the hole
    truth = rec.ground_truth.interpolate(est.t)
    assert np.max(np.linalg.norm(est.position - truth.position, axis=1)) < 0.05


def test_track_without_a_pose_to_write_removes_an_earlier_runs_trajectory_with_its_new_timings(files, tmp_path, capsys):
    d, rec = files
    from evpose.io.map_ply import read_contour_map

    write_contour_map(tmp_path / "wrong.ply", bare_ground_map(read_contour_map(d / "map.ply")))
    out = tmp_path / "e.txt"
    out.write_text("# an earlier run's trajectory\n")
    code = run(["track", str(d / "rec.h5"), "--map", str(tmp_path / "wrong.ply"), "--out", str(out), "--mode", "stpe",
                "--acquire-s", "0", "--timings", str(tmp_path / "t.json"), "--no-progress"])
    assert code == 1 and "nothing" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.json", "wrong.ply"]  # not the old e.txt beside the new t.json
