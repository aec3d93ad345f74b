"""Sweeps: grid parsing, identical tables on the in-process, process-pool and Dask paths, resume after interruption."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

import evpose.eval.runner as runner_mod
from evpose.core.events import EventArray
from evpose.core.recording import Recording
from evpose.errors import ConfigError
from evpose.eval.runner import RunnerConfig
from evpose.eval.sweep import apply_overrides, expand_grid, parse_grid, run_sweep
from evpose.io.h5 import write_recording_h5

GRID = ["window_us=[300,1000,3000,10000]", "enabled=[true,false]"]


def edge_recording(path: Path, seed: int, noise_share: float) -> str:
    """A vertical edge sweeping across a 64x48 sensor plus uniform background noise, written as evpose HDF5."""
    rng = np.random.default_rng(seed)
    w, h = 64, 48
    n_sig = 6000
    t_sig = np.sort(rng.integers(0, 200_000, n_sig))
    x_sig = np.clip((t_sig / 200_000 * w).astype(int) + rng.integers(-1, 2, n_sig), 0, w - 1)
    y_sig = rng.integers(0, h, n_sig)
    n_noise = int(n_sig * noise_share)
    t = np.concatenate([t_sig, rng.integers(0, 200_000, n_noise)])
    x = np.concatenate([x_sig, rng.integers(0, w, n_noise)])
    y = np.concatenate([y_sig, rng.integers(0, h, n_noise)])
    order = np.argsort(t, kind="stable")
    p = rng.integers(0, 2, t.size)
    events = EventArray.from_arrays(t[order], x[order], y[order], p[order])
    write_recording_h5(path, Recording(events, metadata={"width": w, "height": h}))
    return str(path)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> list[str]:
    d = tmp_path_factory.mktemp("recs")
    return [edge_recording(d / f"rec{i}.h5", seed=i, noise_share=0.1 + 0.2 * i) for i in range(4)]


def test_parse_grid_reads_yaml_lists_and_scalars():
    assert parse_grid(["a.b=[1, 2.5]", "c=x"]) == {"a.b": [1, 2.5], "c": ["x"]}
    assert len(expand_grid(parse_grid(GRID))) == 8


@pytest.mark.parametrize("item", ["novalue", "=3", "a=[]"])
def test_malformed_grid_items_are_config_errors(item):
    with pytest.raises(ConfigError):
        parse_grid([item])


def test_unknown_dotted_field_names_the_missing_part():
    base = {"noise_filter": {"window_us": 5000}, "rate_hz": 200.0}
    assert apply_overrides(base, {"noise_filter.window_us": 1000})["noise_filter"]["window_us"] == 1000
    with pytest.raises(ConfigError, match="noise_filter has no 'window'"):
        apply_overrides(base, {"noise_filter.window": 1})
    with pytest.raises(ConfigError, match="is a group"):
        apply_overrides(base, {"noise_filter": 1})


def test_sweep_table_is_identical_in_process_on_a_process_pool_and_on_a_dask_local_cluster(tmp_path, recordings):
    from distributed import LocalCluster

    serial = run_sweep("noise-filter", GRID, recordings, tmp_path / "serial", RunnerConfig(workers=0, progress=False))
    pool = run_sweep("noise-filter", GRID, recordings, tmp_path / "pool", RunnerConfig(workers=2, progress=False))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        dask = run_sweep("noise-filter", GRID, recordings, tmp_path / "dask", RunnerConfig(scheduler=cluster.scheduler_address, progress=False))
    assert serial.table == pool.table == dask.table
    assert len(serial.table["rows"]) == 8 and all(not r["failed"] for r in serial.table["rows"])
    # The filter really depends on its parameters: a longer window keeps more, disabled keeps all.
    shares = {(r["overrides"]["window_us"], r["overrides"]["enabled"]): r["mean_score"] for r in serial.table["rows"]}
    assert shares[(300, True)] < shares[(1000, True)] < shares[(3000, True)] < shares[(10000, True)] <= 1.0
    assert shares[(300, False)] == 1.0
    # The best config file is the full config of the best row.
    best_row = max(serial.table["rows"], key=lambda r: r["mean_score"])
    best = yaml.safe_load((tmp_path / "serial" / "best_config.yaml").read_text())
    assert best == {"enabled": best_row["overrides"]["enabled"], "window_us": best_row["overrides"]["window_us"]}
    assert json.loads((tmp_path / "dask" / "sweep.json").read_text())["table"] == json.loads(json.dumps(serial.table))
    assert "(best)" in (tmp_path / "pool" / "sweep.md").read_text()


def test_interrupted_sweep_resumes_from_finished_jobs(tmp_path, recordings, monkeypatch):
    reference = run_sweep("noise-filter", GRID, recordings[:2], tmp_path / "ref", RunnerConfig(workers=0, progress=False))
    real = runner_mod.execute_job
    calls = []

    def interrupted_after_five(job):
        if len(calls) == 5:
            raise KeyboardInterrupt
        calls.append(job.name)
        return real(job)

    monkeypatch.setattr(runner_mod, "execute_job", interrupted_after_five)
    with pytest.raises(KeyboardInterrupt):
        run_sweep("noise-filter", GRID, recordings[:2], tmp_path / "run", RunnerConfig(workers=0, progress=False))
    assert len(list((tmp_path / "run" / "jobs").glob("*.json"))) == 5

    monkeypatch.setattr(runner_mod, "execute_job", lambda job: (calls.append(job.name), real(job))[1])
    calls.clear()
    resumed = run_sweep("noise-filter", GRID, recordings[:2], tmp_path / "run", RunnerConfig(workers=0, progress=False))
    assert len(calls) == 16 - 5  # only the unfinished jobs ran
    assert resumed.table == reference.table


def test_sweep_cli_writes_table_and_best_config(tmp_path, recordings, capsys):
    from evpose.cli.main import run

    out = tmp_path / "cli"
    code = run(["sweep", "window_us=[1000,3000]", "--recordings", *recordings[:2], "--target", "noise-filter", "--out", str(out), "--workers", "0", "--minimize", "--no-progress"])
    assert code == 0
    text = capsys.readouterr().out
    assert "best configuration: #0" in text  # the shorter window keeps fewer events
    assert yaml.safe_load((out / "best_config.yaml").read_text())["window_us"] == 1000


def test_sweep_cli_rejects_unknown_field_with_exit_code_2(tmp_path, recordings, capsys):
    from evpose.cli.main import run

    code = run(["sweep", "window=[1]", "--recordings", recordings[0], "--target", "noise-filter", "--out", str(tmp_path / "x"), "--workers", "0"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown config field 'window'" in err[0]


def test_unknown_score_is_refused_before_any_job_runs(tmp_path, recordings, monkeypatch):
    # It was found only in the finished table: every job had run and OUT/jobs was written before the error.
    import evpose.eval.sweep as sweep_mod

    monkeypatch.setattr(sweep_mod, "run_jobs", lambda *a, **k: pytest.fail("a job ran"))
    with pytest.raises(ConfigError, match=r"score 'nonsense' is not a metric of this sweep \(metrics: events, events_kept, kept_share\)"):
        run_sweep("noise-filter", ["window_us=[1000]"], recordings[:1], tmp_path / "out", RunnerConfig(workers=0), score="nonsense")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("target", ["tracking", "noise-filter"])
def test_each_targets_metrics_list_holds_its_default_score(target):
    from evpose.eval.sweep import TARGETS

    assert TARGETS[target].score in TARGETS[target].metrics
