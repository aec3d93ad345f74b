"""Jobs for tests/eval/test_pool_stop_s32.py, importable by the pool's spawned workers (not a test module)."""

from __future__ import annotations

import os
import time
from pathlib import Path


def writer_job(out: str, marker: str) -> dict:
    """Start writing OUT (its temporary file exists), say so in MARKER (with this worker's pid), then wait: the run is
    interrupted meanwhile. Returns after 120 s (the test fails: the worker should have been ended)."""
    from evpose.io.atomic import atomic_path

    with atomic_path(Path(out)) as tmp:
        tmp.write_text("partial\n")
        Path(marker).write_text(str(os.getpid()))
        end = time.monotonic() + 120
        while time.monotonic() < end:
            time.sleep(0.05)
    return {"done": True}


def waiter_job(marker: str) -> dict:
    """Return once MARKER exists (the writer job is inside its output), so the parent sees a finished job then."""
    end = time.monotonic() + 120
    while not Path(marker).exists() and time.monotonic() < end:
        time.sleep(0.05)
    return {"pid": os.getpid()}


def tqdm_lock_job() -> dict:
    """What lock a progress bar made in this worker takes."""
    from tqdm import tqdm

    with tqdm(total=1, disable=True):
        pass
    return {"lock_module": type(tqdm.get_lock()).__module__, "lock_type": type(tqdm.get_lock()).__name__}


def released_job(release: str, started: str) -> dict:
    """Say so in STARTED, then wait until RELEASE exists (at most 60 s): a job running or queued when the run is
    interrupted."""
    Path(started).write_text("")
    end = time.monotonic() + 60
    while not Path(release).exists() and time.monotonic() < end:
        time.sleep(0.05)
    return {"released": Path(release).exists()}
