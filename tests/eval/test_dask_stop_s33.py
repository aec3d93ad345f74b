"""An interrupted run on a Dask scheduler cancels its jobs there and returns (session 32 left this path untested).

From the command line (`evpose bench --scheduler tcp://127.0.0.1:8799` against `dask scheduler` + `dask worker`,
/tmp/s33/lead/dint.sh): SIGINT 10 / 30 s in and SIGTERM 10 s in ended it after 0.76-1.21 s, one line, 130 / 143.
"""

from __future__ import annotations

import threading
import time

import pytest

from evpose.eval.cache import Job, ResultCache
from evpose.eval.runner import RunnerConfig, run_jobs

pytest.importorskip("distributed")


class _InterruptingCache(ResultCache):
    """Storing the first finished job raises what Ctrl+C / SIGTERM raise in the CLI."""

    def put(self, job, result):
        raise KeyboardInterrupt


def test_an_interrupted_dask_run_returns_and_leaves_no_job_on_the_scheduler(tmp_path):
    from distributed import Client, LocalCluster

    marker, release = tmp_path / "marker", tmp_path / "release"
    marker.write_text("")
    started = [tmp_path / f"started{k}" for k in range(3)]
    jobs = [Job("done", "pool_stop_jobs_s32:waiter_job", {"marker": str(marker)})]
    jobs += [Job(f"held{k}", "pool_stop_jobs_s32:released_job", {"release": str(release), "started": str(s)})
             for k, s in enumerate(started)]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        try:
            raised: list[BaseException] = []

            def interrupted_run() -> None:
                try:
                    run_jobs(jobs, _InterruptingCache(tmp_path / "jobs"), RunnerConfig(scheduler=cluster.scheduler_address, progress=False))
                except BaseException as exc:  # noqa: BLE001 -- the KeyboardInterrupt is what is checked
                    raised.append(exc)

            runner = threading.Thread(target=interrupted_run, daemon=True)
            runner.start()
            runner.join(60)  # a hang detector (the run returns in about a second), not a speed check
            assert not runner.is_alive(), "the interrupted run did not return while a job was still running"
            assert len(raised) == 1 and isinstance(raised[0], KeyboardInterrupt)
            with Client(cluster.scheduler_address, set_as_default=False) as client:
                left = None
                for _ in range(200):  # the cancellation reaches the scheduler asynchronously
                    left = client.run_on_scheduler(lambda dask_scheduler: sorted(dask_scheduler.tasks))
                    if not left:
                        break
                    time.sleep(0.05)
                assert left == []
            release.write_text("")
            time.sleep(0.5)
            # One worker thread: at most the job after the finished one had started; the ones queued behind it never do.
            assert sum(s.exists() for s in started) <= 1
        finally:
            release.write_text("")  # lets the job threads that had started end before the cluster closes
