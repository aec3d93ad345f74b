"""An interrupted pool run ends its workers, which unwind their outputs (evpose.eval.pool_workers).

Session 32: a SIGTERM to ``evpose bench`` while its pool ran jobs printed "terminated" at once but the process lived on
8-46 s: the interpreter's exit joined the pool, waiting for the running jobs, which went on writing.
"""

from __future__ import annotations

import os

import pytest

from evpose.eval.cache import Job, ResultCache
from evpose.eval.runner import RunnerConfig, run_jobs


class _InterruptingCache(ResultCache):
    """Storing the first finished job raises what Ctrl+C / SIGTERM raise in the CLI."""

    def put(self, job, result):
        raise KeyboardInterrupt


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_an_interrupted_pool_ends_its_running_workers_and_their_outputs(tmp_path):
    out, marker = tmp_path / "out" / "result.txt", tmp_path / "writer.pid"
    jobs = [Job("writer", "pool_stop_jobs_s32:writer_job", {"out": str(out), "marker": str(marker)}),
            Job("waiter", "pool_stop_jobs_s32:waiter_job", {"marker": str(marker)})]
    with pytest.raises(KeyboardInterrupt):
        run_jobs(jobs, _InterruptingCache(tmp_path / "jobs"), RunnerConfig(workers=2, progress=False))
    writer = int(marker.read_text())
    # Returned: the writer was ended (not waited for), its output never written and its temporary file removed.
    assert _gone(writer)
    assert not out.exists()
    assert sorted(p.name for p in out.parent.iterdir()) == []


def test_an_uninterrupted_pool_still_runs_every_job_in_its_workers(tmp_path):
    markers = [tmp_path / f"m{k}" for k in range(3)]
    for m in markers:
        m.write_text("")
    jobs = [Job(f"w{k}", "pool_stop_jobs_s32:waiter_job", {"marker": str(m)}) for k, m in enumerate(markers)]
    outcomes = run_jobs(jobs, None, RunnerConfig(workers=2, progress=False))
    assert [o["ok"] for o in outcomes] == [True, True, True]
    assert all(o["result"]["pid"] != os.getpid() for o in outcomes)


def test_a_workers_progress_bars_hold_no_semaphore_of_the_shared_resource_tracker():
    # tqdm's default lock is a multiprocessing semaphore: a worker ended by an interrupt left the tracker warning
    # "There appear to be 1 leaked semaphore objects to clean up at shutdown" after the command's line.
    jobs = [Job("lock", "pool_stop_jobs_s32:tqdm_lock_job", {}), Job("w", "pool_stop_jobs_s32:waiter_job", {"marker": __file__})]
    outcomes = run_jobs(jobs, None, RunnerConfig(workers=2, progress=False))  # two jobs: the pool, not this process
    assert outcomes[0]["ok"], outcomes[0]
    assert outcomes[0]["result"] == {"lock_module": "_thread", "lock_type": "RLock"}
