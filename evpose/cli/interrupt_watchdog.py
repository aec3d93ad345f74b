"""A native thread that ends the process when a Ctrl+C or SIGTERM is not acted on within a grace period.

Python runs signal handlers in the main thread between bytecodes, so a signal arriving inside a long numba kernel (which
holds the GIL and never checks for signals) waited for the kernel to return: ``build-map --cell`` on the landing cloud
spent up to a minute in one raster kernel, a minute in which Ctrl+C did nothing (session 30, /tmp/s30/fuzz30/), and
session 31 saw ``bench`` ignore a SIGTERM 3-3.5 s after its start for over 60 s (2 of 9 tries, not reproduced under
faulthandler; /tmp/s31/fuzz31/sig/lat.py; session 32 found that one: not a kernel but the job pool, which the
interpreter's exit joined after the watchdog was disarmed, :mod:`evpose.eval.pool_workers`). A Python thread cannot
help: it needs the GIL the kernel holds.

So :func:`start` starts a thread running a numba ``cfunc`` (native code, no GIL) and points Python's signal wakeup fd
(:func:`signal.set_wakeup_fd`) at a pipe it reads: Python's C-level handler writes the signal's number there at once,
whatever the main thread is doing. The thread then waits ``grace_s``; if :func:`stop` has not been called by then (the
main thread did not unwind through :func:`evpose.cli.main.run`), it deletes the temporary files of the outputs being
written (:mod:`evpose.io.atomic` keeps it told of them), prints the same line ``run`` would ("evpose NAME:
interrupted" / "terminated") and ends the process with 130 / 143, as the shell expects. While an output set is being
renamed (SIGINT/SIGTERM held, :func:`evpose.io.atomic._signals_held`) it waits for the renames to finish first.
A temporary *folder* (an output written as a folder) is only removed when empty: native code does not walk folders.

Cost: the kernel is cached (``cache=True``); loading it takes ~10 ms once numba is initialised, so only commands that
use numba anyway start it (:data:`evpose.cli.main.WATCHED_COMMANDS`).
"""

from __future__ import annotations

import ctypes
import os
import signal
import threading

import numpy as np

from evpose.cli.interrupt_kernel import INT_MSG_AT, PATHS_AT, SIZE, TERM_MSG_AT, watch

_state: np.ndarray | None = None
_thread_started = False
_previous_fd: int | None = None


def start(name: str, grace_s: float = 1.0, quiet: bool = False) -> bool:
    """Arm the watchdog for ``evpose NAME`` (main thread only); False where it cannot run (not the main thread, SIGINT
    and SIGTERM both without a Python handler, no pthreads). ``quiet``: print nothing when it ends the process (a
    worker of a process pool, whose parent prints the line: :mod:`evpose.eval.pool_workers`)."""
    global _state, _thread_started, _previous_fd
    if threading.current_thread() is not threading.main_thread():
        return False
    if _state is None:
        _state = np.zeros(SIZE // 8, np.int64)
    st = _state
    st[2] = 1  # done until armed below: a byte left in the pipe from before must not end this run
    raw = st.view(np.uint8)
    for at, slot, word in ((INT_MSG_AT, 4, "interrupted"), (TERM_MSG_AT, 5, "terminated")):
        line = f"evpose {name}: {word}\n".encode()[:250]
        raw[at:at + len(line)] = np.frombuffer(line, np.uint8)
        st[slot] = 0 if quiet else len(line)
    st[1] = int(grace_s * 1e6)
    st[3] = 0
    set_paths(())
    if not _thread_started:
        try:
            r, w = os.pipe()
            os.set_blocking(w, False)
            libc = ctypes.CDLL(None)
            tid = ctypes.c_ulong()
            st[0] = r
            if libc.pthread_create(ctypes.byref(tid), None, ctypes.c_void_p(watch.address), ctypes.c_void_p(st.ctypes.data)) != 0:
                return False
            libc.pthread_detach(tid)
        except (OSError, AttributeError, ImportError):
            return False
        _thread_started = True
        start.write_fd = w
        # A child forked without exec (os.fork, multiprocessing's "fork"; evpose's own pools spawn) keeps the wakeup
        # fd: a SIGTERM sent to the child alone would reach this pipe and end the parent. It has no watchdog thread.
        os.register_at_fork(after_in_child=_forget_in_child)
    _previous_fd = signal.set_wakeup_fd(start.write_fd, warn_on_full_buffer=False)
    st[2] = 0
    return True


def _forget_in_child() -> None:
    global _previous_fd
    if _previous_fd is not None:
        try:
            signal.set_wakeup_fd(-1)
        except ValueError:  # not the main thread of the child
            pass
        _previous_fd = None


def stop() -> None:
    """Disarm: the command unwound (or finished) by itself."""
    global _previous_fd
    if _state is None or _previous_fd is None:
        return
    _state[2] = 1
    signal.set_wakeup_fd(_previous_fd)
    _previous_fd = None


def set_paths(paths) -> None:
    """The temporary files the watchdog deletes if it ends the process (replaces the earlier list)."""
    if _state is None:
        return
    raw = _state.view(np.uint8)
    data = b"".join(os.fsencode(str(p)) + b"\0" for p in paths)[: SIZE - PATHS_AT - 2] + b"\0\0"
    raw[PATHS_AT:PATHS_AT + len(data)] = np.frombuffer(data, np.uint8)


def set_held(held: bool) -> None:
    """An output set is being renamed: the watchdog waits until it is done."""
    if _state is not None:
        _state[3] = int(held)
