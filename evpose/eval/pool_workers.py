"""The local pool's worker processes, and how an interrupted run ends them.

Session 32 (``/tmp/s32/sig32/sig.py``): ``evpose bench`` took 8-46 s to exit after a SIGTERM that landed while its
pool ran jobs (1 of 1 tries at 3.5 s; session 31 saw it 2 of 9 times). The command itself unwound at once and printed
its line, but the interpreter's exit then joined the pool (``concurrent.futures`` registers that at exit), which waited
for the jobs the workers were running (a simulation, a tracking run) to finish; the watchdog
(:mod:`evpose.cli.interrupt_watchdog`) had already been disarmed by the unwinding. So on an interrupt the parent now
ends its workers (:func:`stop_workers`) before it unwinds, and each worker is set up (:func:`init_worker`) to end
cleanly on SIGTERM: Python code unwinds (the temporary files of the outputs it was writing go, :mod:`evpose.io.atomic`)
and the process exits with 143; a worker inside a numba kernel, which never checks for signals, is ended by its own
quiet watchdog after :data:`WORKER_GRACE_S`, which deletes those files first. Workers ignore SIGINT: a terminal's
Ctrl+C reaches the whole process group, and the parent decides (a worker's KeyboardInterrupt printed a traceback).
"""

from __future__ import annotations

import os
import signal
import threading
import time

WORKER_GRACE_S = 0.5
"""Seconds a worker has to unwind after SIGTERM before its watchdog ends it: under the parent's own grace period
(:data:`evpose.cli.main.WATCHDOG_GRACE_S`, 1.5 s), so the parent, waiting for its workers, still unwinds in time."""

STOP_WAIT_S = 1.0
"""Longest the parent waits for its workers to end after SIGTERM before it kills those left (with SIGKILL)."""


class WorkerStop(SystemExit):
    """SIGTERM in a pool worker: unwinds the job (``execute_job`` catches ``Exception`` only) and ends the process."""


def _stop(signum, frame) -> None:
    raise WorkerStop(128 + signum)


def _tell_watchdog(paths, held) -> None:
    from evpose.cli import interrupt_watchdog

    interrupt_watchdog.set_paths(paths)
    interrupt_watchdog.set_held(held)


def init_worker() -> None:
    """Initializer of each worker process (its main thread, before any job)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # tqdm's default lock holds a multiprocessing semaphore, registered with the pool's shared resource tracker: a
    # worker ended before finalising it left the tracker warning "There appear to be 1 leaked semaphore objects" after
    # the command's line (`bench` SIGTERM at 150 s). A worker's bars are its own: a thread lock does.
    from tqdm import tqdm

    tqdm.set_lock(threading.RLock())
    try:
        from evpose.cli import interrupt_watchdog
        from evpose.io import atomic

        if interrupt_watchdog.start("worker", WORKER_GRACE_S, quiet=True):
            atomic.LISTENERS.append(_tell_watchdog)
            _tell_watchdog(tuple(atomic._LIVE), False)
    except Exception:  # noqa: BLE001 - no numba/pthreads: SIGTERM still unwinds between kernels
        pass
    # Last: until here SIGTERM ends the worker at once (nothing written yet); raised while numba loaded, it was the
    # pool's "Exception in initializer" and a 30-line traceback.
    signal.signal(signal.SIGTERM, _stop)


def run_job(job) -> dict:
    """:func:`evpose.eval.runner.execute_job` in a worker; a SIGTERM ends the process once the job has unwound (the pool
    would otherwise hand it the next job)."""
    from evpose.eval.runner import execute_job

    try:
        return execute_job(job)
    except WorkerStop as exc:
        os._exit(int(exc.code))


def stop_workers(current, wait_s: float = STOP_WAIT_S) -> None:
    """SIGTERM to each worker (``current()``: the pool's ``multiprocessing.Process`` list now), then wait up to
    ``wait_s`` in all for them to end; kill (SIGKILL) those left. Asked again after each round: a pool that starts a
    process per job (``fresh_process``) may have replaced one that finished just then, and the new one would run the
    next job."""
    seen: set[int] = set()
    for _ in range(3):
        processes = [p for p in current() if p is not None and p.pid not in seen]
        if not processes:
            return
        seen.update(p.pid for p in processes)
        _stop_now(processes, wait_s)


def _stop_now(processes, wait_s: float) -> None:
    for p in processes:
        try:
            p.terminate()
        except (OSError, ValueError, AttributeError):  # already gone / closed
            pass
    deadline = time.monotonic() + wait_s
    for p in processes:
        try:
            p.join(max(0.0, deadline - time.monotonic()))
        except (OSError, ValueError, AssertionError):
            pass
    for p in processes:
        try:
            if p.is_alive():
                p.kill()
                p.join(0.2)
        except (OSError, ValueError, AssertionError):
            pass
