"""The job runner and its per-job cache: failures, identity, serial vs pool."""

from __future__ import annotations

import pytest

from evpose.errors import ConfigError
from evpose.eval.cache import Job, ResultCache
from evpose.eval.runner import RunnerConfig, execute_job, run_jobs


def test_job_key_depends_on_function_and_parameters_only():
    a = Job("a", "evpose.eval.jobs:noise_filter_job", {"config": {"window_us": 1}, "recording": "r"})
    b = Job("renamed", "evpose.eval.jobs:noise_filter_job", {"recording": "r", "config": {"window_us": 1}})
    c = Job("a", "evpose.eval.jobs:noise_filter_job", {"config": {"window_us": 2}, "recording": "r"})
    assert a.key() == b.key() != c.key()


def test_failed_job_is_reported_in_one_line_and_not_cached(tmp_path):
    bad = Job("bad", "evpose.eval.jobs:noise_filter_job", {"config": {"window_us": 1000}, "recording": str(tmp_path / "missing.h5")})
    out = execute_job(bad)
    assert not out["ok"] and "\n" not in out["error"] and "missing.h5" in out["error"]
    cache = ResultCache(tmp_path / "jobs")
    outcomes = run_jobs([bad], cache, RunnerConfig(workers=0, progress=False))
    assert not outcomes[0]["ok"] and cache.get(bad) is None


def test_unknown_config_field_inside_a_job_is_an_error_outcome(tmp_path):
    job = Job("j", "evpose.eval.jobs:noise_filter_job", {"config": {"windw_us": 1000}, "recording": "x"})
    out = execute_job(job)
    assert not out["ok"] and "windw_us" in out["error"]


def test_duplicate_jobs_are_rejected():
    j = Job("a", "evpose.eval.jobs:noise_filter_job", {"x": 1})
    with pytest.raises(ConfigError):
        run_jobs([j, Job("b", j.fn, dict(j.params))], None, RunnerConfig(workers=0, progress=False))


def test_cache_ignores_a_file_whose_parameters_do_not_match(tmp_path):
    cache = ResultCache(tmp_path)
    j = Job("a", "m:f", {"x": 1})
    cache.put(j, {"metrics": {"v": 1}})
    assert cache.get(j) == {"metrics": {"v": 1}}
    text = cache.path(j).read_text().replace('"x": 1', '"x": 2')
    cache.path(j).write_text(text)
    assert cache.get(j) is None


def test_a_code_change_invalidates_cached_results(tmp_path, monkeypatch):
    import evpose.eval.cache as cache_mod

    cache = ResultCache(tmp_path)
    j = Job("a", "m:f", {"x": 1})
    cache.put(j, {"metrics": {"v": 1}})
    assert cache.get(j) is not None
    monkeypatch.setattr(cache_mod, "code_version", lambda: "edited-source")
    assert cache.get(j) is None
