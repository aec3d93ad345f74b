"""Run a list of jobs on a local process pool (default), in this process, or on a Dask cluster.

Every job is a pure function of its parameters (see :class:`~evpose.eval.cache.Job`),
so where it runs cannot change its result; results come back in job order
whatever the completion order. Each finished job is stored in the
:class:`~evpose.eval.cache.ResultCache` immediately, so an interrupted run,
restarted with the same output folder, only runs what is missing.
"""

from __future__ import annotations

import enum
import importlib
import json
import traceback
from dataclasses import dataclass
from typing import Callable

import numpy as np

from evpose.errors import ConfigError, EvposeError
from evpose.eval.cache import Job, ResultCache


class Backend(str, enum.Enum):
    """Where jobs run."""

    LOCAL = "local"
    """A pool of ``workers`` processes on this machine (0 or 1 worker: this process, serially)."""
    DASK = "dask"
    """A Dask distributed scheduler at ``scheduler`` (``tcp://host:8786``, or a LocalCluster's address)."""


@dataclass(frozen=True)
class RunnerConfig:
    """How a list of jobs is executed."""

    workers: int = 2
    """Local worker processes; 0 or 1 runs the jobs serially in this process, processes."""
    scheduler: str | None = None
    """Address of a Dask scheduler; when set, jobs run there instead of locally."""
    progress: bool = True
    """Show a progress bar on stderr."""
    fresh_process: bool = False
    """Local pool only: a new worker process per job, so per-job peak memory is the job's own (costs an import per job)."""

    @property
    def backend(self) -> Backend:
        return Backend.DASK if self.scheduler else Backend.LOCAL


def _jsonable(obj):
    """numpy scalars/arrays -> Python numbers/lists (json.dumps default hook)."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, enum.Enum):
        return obj.value
    raise TypeError(f"not JSON-serialisable: {type(obj).__name__}")


def resolve(fn: str) -> Callable:
    """``"pkg.module:function"`` -> the function."""
    module, _, name = fn.partition(":")
    return getattr(importlib.import_module(module), name)


def execute_job(job: Job) -> dict:
    """Run one job anywhere; returns ``{"ok": True, "result": ...}`` or ``{"ok": False, "error": one line}``.

    The result goes through a JSON round trip so a fresh result is identical to
    one read back from the cache.
    """
    try:
        result = resolve(job.fn)(**job.params)
        return {"ok": True, "result": json.loads(json.dumps(result, default=_jsonable))}
    except EvposeError as exc:
        return {"ok": False, "error": str(exc)}
    except Exception as exc:  # noqa: BLE001 - one failed job must not take the suite down
        last = traceback.extract_tb(exc.__traceback__)[-1]
        return {"ok": False, "error": f"{type(exc).__name__}: {exc} ({last.filename}:{last.lineno})"}


def _progress(total: int, initial: int, enabled: bool, desc: str):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, disable=not enabled, desc=desc, unit="job", leave=False)


def run_jobs(jobs: list[Job], cache: ResultCache | None = None, config: RunnerConfig = RunnerConfig(), desc: str = "jobs") -> list[dict]:
    """Run ``jobs`` (skipping those already in ``cache``); returns one outcome dict per job, in order.

    An outcome is ``{"ok": bool, "result" or "error", "cached": bool}``.
    """
    keys = [j.key() for j in jobs]
    if len(set(keys)) != len(keys):
        raise ConfigError("two jobs have the same function and parameters")
    outcomes: list[dict | None] = [None] * len(jobs)
    todo = []
    for i, job in enumerate(jobs):
        hit = cache.get(job) if cache is not None else None
        if hit is not None:
            outcomes[i] = {"ok": True, "result": hit, "cached": True}
        else:
            todo.append(i)

    def finish(i: int, out: dict) -> None:
        out["cached"] = False
        outcomes[i] = out
        if out["ok"] and cache is not None:
            cache.put(jobs[i], out["result"])

    bar = _progress(len(jobs), len(jobs) - len(todo), config.progress, desc)
    try:
        if not todo:
            pass
        elif config.backend is Backend.DASK:
            _run_dask(jobs, todo, config.scheduler, finish, bar)
        elif config.workers <= 1 or len(todo) == 1:
            for i in todo:
                finish(i, execute_job(jobs[i]))
                bar.update(1)
        else:
            _run_pool(jobs, todo, config.workers, finish, bar, config.fresh_process)
    finally:
        bar.close()
    return outcomes  # type: ignore[return-value]


def _run_pool(jobs, todo, workers, finish, bar, fresh_process: bool = False) -> None:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from evpose.eval.pool_workers import init_worker, run_job, stop_workers

    # spawn, not fork: workers must not inherit threads (tqdm, numba, dask) or half-held locks.
    ctx = multiprocessing.get_context("spawn")
    extra = {"max_tasks_per_child": 1} if fresh_process else {}
    with ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx, initializer=init_worker, **extra) as pool:
        futures = {pool.submit(run_job, jobs[i]): i for i in todo}
        try:
            for fut in as_completed(futures):
                finish(futures[fut], fut.result())
                bar.update(1)
        except BaseException:
            # Interrupted: drop queued jobs (finished ones are already in the cache for the rerun) and end the running
            # ones: the interpreter's exit joined the pool, waiting 8-46 s for them (evpose.eval.pool_workers).
            # (Not Future.cancel() first: the pool's thread then failed on the cancelled ones with InvalidStateError.)
            stop_workers(lambda: list((pool._processes or {}).values()))
            # Flags the shutdown (no worker or job starts any more) and joins the pool's thread, which, its workers
            # gone, ends at once. shutdown(wait=False) let that thread run on and fail on the pool it had emptied
            # ("TypeError: object of type 'NoneType' has no len()", a traceback after the command's line).
            pool.shutdown(wait=True, cancel_futures=True)
            raise


def _run_dask(jobs, todo, address, finish, bar) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--scheduler needs the 'distributed' package (pip install 'dask[distributed]')") from None
    try:
        client = Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError(f"cannot connect to the Dask scheduler at {address} ({exc})") from None
    try:
        futures = {client.submit(execute_job, jobs[i], key=f"evpose-job-{jobs[i].key()}", pure=False): i for i in todo}
        try:
            # as_completed looks up "the current client"; make ours current only for this loop.
            with client.as_current():
                for fut in as_completed(list(futures)):
                    finish(futures[fut], fut.result())
                    bar.update(1)
        except BaseException:
            client.cancel(list(futures))
            raise
    finally:
        client.close()
