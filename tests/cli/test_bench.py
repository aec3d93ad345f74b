"""``evpose bench``: a tiny real suite end to end (simulate, track, peers, report) and resuming from its results."""

from __future__ import annotations

import json

import pytest

from evpose.eval.bench_run import run_bench
from evpose.eval.report import write_report
from evpose.eval.runner import RunnerConfig
from evpose.eval.suite import Study, SuiteConfig, SuiteName

TINY = SuiteConfig(
    width=64,
    height=48,
    seconds=0.1,
    seed=0,
    studies=(
        Study("systems", "Latency of the systems (paper Table I)", ("landing",), ("stpe", "no-such-mode"), (200.0,)),
        Study("slam", "Event-based SLAM", ("landing",), ("slam-event",), (0.0,)),
    ),
    cloud_density_per_m2=20.0,
)


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    run = run_bench(SuiteName.QUICK, out, RunnerConfig(workers=0, progress=False), micro=False, peers=True, config=TINY)
    write_report(run, out, "in-process, serial")
    return out, run


def test_tiny_suite_tracks_and_writes_markdown_and_json(first_run):
    out, run = first_run
    assert all(s["ok"] for s in run.simulations), run.simulations
    stpe = run.runs["landing/stpe/200hz"]
    assert stpe["ok"], stpe.get("error")
    metrics, timing = stpe["result"]["metrics"], stpe["result"]["timing"]
    assert 0 < metrics["steps"] <= 20  # at most 0.1 s at 200 Hz (the tracker may start after a warm-up)
    assert metrics["events_in"] > 0 and 0.0 <= metrics["filtered_share"] <= 1.0
    assert timing["latency_ms"]["total"]["n"] == metrics["steps"] - 1 and timing["peak_rss_mb"] > 0  # first step reported apart
    assert timing["first_step_ms"] > 0
    assert "ate_m" in metrics["accuracy"] or "error" in metrics["accuracy"]
    # A mode the tracker does not offer is reported, not fatal.
    missing = run.runs["landing/no-such-mode/200hz"]
    assert not missing["ok"] and "not available" in missing["error"]
    md = (out / "report.md").read_text()
    assert "Latency of the systems (paper Table I)" in md and "| stpe |" in md and "not available" in md
    assert "## Peer comparison: dv-processing" in md
    data = json.loads((out / "report.json").read_text())
    assert data["runs"]["landing/stpe/200hz"]["result"]["metrics"] == metrics


def test_peer_comparison_runs_on_the_suite_recording(first_run):
    pytest.importorskip("dv_processing")
    _, run = first_run
    assert run.peers["ok"] and run.peers["result"]["metrics"]["available"]
    assert run.peers["result"]["timing"]["kept_agreement"] == 1.0


def test_rerun_resumes_from_finished_jobs_with_identical_results(first_run):
    out, run = first_run
    again = run_bench(SuiteName.QUICK, out, RunnerConfig(workers=0, progress=False), micro=False, peers=True, config=TINY)
    assert all(s["cached"] for s in again.simulations)
    assert again.runs["landing/stpe/200hz"]["cached"]
    assert again.runs["landing/stpe/200hz"]["result"] == run.runs["landing/stpe/200hz"]["result"]
    # The failed run is retried, not cached.
    assert not again.runs["landing/no-such-mode/200hz"]["cached"]


def test_bench_cli_rejects_an_unknown_suite(capsys):
    from evpose.cli.main import run

    assert run(["bench", "--suite", "huge"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'huge'" in err[0] and "quick" in err[0]


def test_tracking_sweep_runs_on_a_recording_with_its_map(first_run, tmp_path):
    from evpose.eval.suite import scenario_specs
    from evpose.eval.scenarios import scenario_paths
    from evpose.eval.sweep import run_sweep

    out, _ = first_run
    rec, cmap = scenario_paths(scenario_specs(TINY)[0], out / "data")
    spec = f"{rec}::{cmap}"
    res = run_sweep("tracking", ["rate_hz=[100,200]"], [spec], tmp_path / "sweep", RunnerConfig(workers=0, progress=False))
    rows = res.table["rows"]
    assert [r["overrides"]["rate_hz"] for r in rows] == [100, 200]
    assert all(not r["failed"] for r in rows), rows
    assert all("ate_mean_m" in r["recordings"][spec] and "ok_share" in r["recordings"][spec] for r in rows)
    assert res.table["best"] is not None
    from evpose.tracker.config import load_config

    best = load_config(tmp_path / "sweep" / "best_config.yaml")  # a complete, loadable tracker config
    assert best.rate_hz == rows[res.table["best"]]["overrides"]["rate_hz"]


def test_tracking_sweep_on_a_recording_without_map_reports_the_missing_map(first_run, tmp_path):
    from evpose.eval.suite import scenario_specs
    from evpose.eval.scenarios import scenario_paths
    from evpose.eval.sweep import run_sweep

    out, _ = first_run
    rec, _ = scenario_paths(scenario_specs(TINY)[0], out / "data")
    res = run_sweep("tracking", ["rate_hz=[100]"], [str(rec)], tmp_path / "sweep", RunnerConfig(workers=0, progress=False))
    assert res.table["rows"][0]["failed"] == [str(rec)]
    assert "needs a contour map" in res.table["rows"][0]["recordings"][str(rec)]["error"]
    assert res.best_config is None


def test_suite_on_a_dask_local_cluster_gives_the_same_metrics(first_run, tmp_path):
    from distributed import LocalCluster

    out, run = first_run
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        dask = run_bench(SuiteName.QUICK, tmp_path / "dask", RunnerConfig(scheduler=cluster.scheduler_address, progress=False), data_dir=out / "data", micro=False, peers=False, config=TINY)
    name = "landing/stpe/200hz"
    assert not dask.runs[name]["cached"]  # really recomputed on the cluster
    assert dask.runs[name]["result"]["metrics"] == run.runs[name]["result"]["metrics"]


def test_slam_study_runs_slam_on_the_suite_recording_and_reports_why_it_did_not_initialise(first_run):
    out, run = first_run
    slam = run.runs["landing/slam-event"]
    assert slam["ok"], slam.get("error")
    # 0.1 s at 64x48 is too little for an MCI: the run is reported with the reason, not dropped.
    assert slam["result"]["metrics"]["slam"]["error"].startswith("not initialised")
    md = (out / "report.md").read_text()
    assert "## Event-based SLAM" in md and "| landing/slam-event |" in md and "not initialised" in md


@pytest.fixture(scope="module")
def slam_recording():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "slam"))
    from slam_synthetic import make_recording

    return make_recording(duration_s=0.6, speed=1.5, seed=11)


def test_slam_job_reports_the_slam_papers_metrics_and_per_mci_latency(slam_recording):
    from evpose.eval.report import SLAM_HEAD, slam_row
    from evpose.eval.suite import slam_and_measure

    a = slam_and_measure(slam_recording, "slam-event")
    m, t = a["metrics"], a["timing"]
    s = m["slam"]
    assert m["mcis"] > 3 and m["correct_scale"] and s["maps"] >= 1
    assert s["stability_m_s"] == pytest.approx(s["tracked_time_s"] * s["distance_m"])
    assert 0.5 < s["tracked_fraction"] <= 1.0 and s["rpe_trans_per_m"] > 0
    assert t["latency_ms"]["total"]["n"] == m["mcis"] - 1 and t["latency_ms"]["mci"]["median_ms"] > 0  # first MCI reported apart
    assert a["metrics"] == slam_and_measure(slam_recording, "slam-event")["metrics"]  # deterministic
    row = slam_row("synthetic/slam-event", {"ok": True, "result": a})
    assert len(row) == len(SLAM_HEAD) and row[1] == str(s["maps"]) and "Sim(3)" in row[-1]


def test_event_inertial_slam_job_is_not_scale_corrected(slam_recording):
    from evpose.eval.suite import slam_and_measure

    m = slam_and_measure(slam_recording, "slam-event-inertial")["metrics"]
    assert not m["correct_scale"]
    assert all(p["scale"] == 1.0 for p in m["slam"]["per_map"])


def test_quick_suite_has_a_slam_study_with_both_modes():
    from evpose.eval.suite import SUITES, run_keys, tracking_jobs

    cfg = SUITES[SuiteName.QUICK]
    jobs = {j.name: j for j in tracking_jobs(cfg, "/nonexistent")}
    for mode in ("slam-event", "slam-event-inertial"):
        assert jobs[f"landing/{mode}"].fn == "evpose.eval.suite:scenario_slam_job"
    assert ("landing", "slam-event", 0.0) in run_keys(SUITES[SuiteName.FULL])
