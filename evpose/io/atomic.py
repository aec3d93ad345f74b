"""Atomic output: write to a temporary sibling, then rename, so no half-written file is ever left.

A command with several outputs (``slam``: a trajectory per map, the longest one and a summary; ``track --timings
--smoothed``; ``simulate``: recording, cloud and edges; ``eval --json --plots``...) writes them inside
:func:`output_set`: each :func:`atomic_path` then leaves its finished temporary file in place, and the set renames
them all onto their names together at the end, with SIGINT and SIGTERM held off while it does. An interrupt before
that leaves the previous run's outputs as they were and no temporary file; one during it is acted on once every
output is in place. Written one after the other, a Ctrl+C between two left e.g. ``EST.map0.txt`` without
``EST.slam.json``, or a new trajectory beside the summary of the run before.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import os
import re
import shutil
import signal
import tempfile
import threading
from pathlib import Path

from evpose.errors import InputError, OutputError

_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS}
"""Errors only a write raises, which no input causes: a full disk or quota, a file too large for the file system, a
read-only remount (EIO is left out: a damaged input read inside the output's block raises it too)."""


def write_failure(exc: BaseException) -> str | None:
    """Why writing an output failed, if ``exc`` is such a failure (else None): an OSError of :data:`_WRITE_ERRNOS`,
    or HDF5's report of one, which h5py raises as an OSError or RuntimeError holding "file write failed: ...
    error message = 'No space left on device'" (a full disk ended `convert` in that 3-line traceback, then a crash)."""
    if isinstance(exc, (OSError, RuntimeError)):
        m = re.search(r"file write failed.*?error message = '([^']*)'", str(exc), re.S)
        if m:
            return m.group(1)
    if isinstance(exc, OSError) and exc.errno in _WRITE_ERRNOS:
        return os.strerror(exc.errno)
    return None


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _check_not_input(dst: Path, inputs: tuple[Path, ...]) -> None:
    from evpose.io.open import recording_files

    for src in inputs:
        try:
            if src.exists() and dst.exists() and os.path.samefile(src, dst):
                raise InputError(dst, "refusing to overwrite an input file")
            if not dst.is_file():
                continue
            # A recording is also read from other files: `convert ecd ecd/events.txt` replaced the events it was
            # converting, `eval EST seq-events_left.h5 --json mocap_data.txt` the ground truth it was read against.
            for part in recording_files(src):
                if os.path.samefile(part, dst):
                    raise InputError(dst, f"refusing to overwrite a file the input recording {src} is read from")
        except OSError:
            continue


def _check_target(dst: Path, is_dir: bool) -> None:
    """``dst`` can be created: not a folder where a file goes (or the reverse), under a writable folder (or one we can make)."""
    if not is_dir and dst.is_dir():
        raise InputError(dst, "output is an existing folder; give a file name")
    if dst.exists() and not dst.is_file() and not dst.is_dir():
        # As root, `--out /dev/null` (or /dev/full) replaced the device node with a regular file: the atomic rename
        # works on any name in a writable folder.
        raise OutputError(dst, "output exists and is not a regular file (a device, pipe or socket); give a file name")
    if is_dir and dst.exists() and not dst.is_dir():
        raise InputError(dst, "output folder exists and is a file")
    ancestor = dst.parent if str(dst.parent) else Path(".")
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise InputError(dst, f"cannot create the output: {ancestor} is a file, not a folder")
    if not os.access(ancestor, os.W_OK):
        raise OutputError(dst, "output folder is not writable")
    # access() says yes to root for any folder on a writable mount, /proc and /sys included, where nothing can be
    # created: `bench --out /proc/x` failed only after 40 s of work. A real (empty, removed) folder is the test.
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".evpose-probe-", dir=ancestor))
    except OSError as exc:
        raise OutputError(dst, f"cannot create anything in {ancestor}: {exc.strerror or exc}") from None


def check_outputs(outputs, inputs=(), folders=()) -> None:
    """Refuse, before any work, outputs that would replace an input or cannot be written.

    A command calls this first so that a bad ``--out`` fails in a second with nothing written, not after a
    long run (or after writing its other outputs). ``folders`` are output paths that are directories.
    """
    ins = tuple(Path(p) for p in inputs if p is not None)
    seen: set[Path] = set()
    for dst, is_dir in [(o, False) for o in outputs] + [(f, True) for f in folders]:
        if dst is None:
            continue
        dst = Path(dst)
        if dst.resolve() in seen:
            # e.g. `track --out a.txt --timings a.txt`: the second write replaced the first, exit 0.
            raise InputError(dst, "given for two outputs; each output needs its own file")
        seen.add(dst.resolve())
        _check_not_input(dst, ins)
        for src in ins:
            if dst.resolve() == src.resolve():
                raise InputError(dst, "refusing to overwrite an input file")
        _check_target(dst, is_dir)


_LIVE: dict[Path, None] = {}
"""The temporary files and folders of outputs being written (in this process), oldest first."""
LISTENERS: list = []
"""Callables told ``(live temporaries, held)`` whenever :data:`_LIVE` changes or an output set starts or ends its
renames: :mod:`evpose.cli.interrupt_watchdog`, which deletes them itself when an interrupt is not acted on in time
(a numba kernel holding the main thread)."""


def _tell(held: bool = False) -> None:
    for fn in LISTENERS:
        fn(tuple(_LIVE), held)


def _live(path: Path, live: bool) -> None:
    if live:
        _LIVE[path] = None
    else:
        _LIVE.pop(path, None)
    _tell()


_PENDING: contextvars.ContextVar[dict | None] = contextvars.ContextVar("evpose_output_set", default=None)
"""The open :func:`output_set`: its finished outputs ``(tmp, dst, is_dir, holder)`` under "files", the earlier run's
files it removes under "remove" (None when none is open)."""


def _discard(tmp: Path, holder: Path | None) -> None:
    _live(tmp, False)
    if holder is not None:
        _live(holder, False)
    if tmp.is_dir():
        shutil.rmtree(tmp, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
    if holder is not None:
        shutil.rmtree(holder, ignore_errors=True)


def _publish(tmp: Path, dst: Path, is_dir: bool) -> None:
    if is_dir and dst.exists():
        shutil.rmtree(dst) if dst.is_dir() else dst.unlink()
    os.replace(tmp, dst)
    _live(tmp, False)


@contextlib.contextmanager
def output_set(remove=()):
    """Hold back every :func:`atomic_path` output inside the block and rename them all together when it ends without
    an error (else delete them all): the outputs appear as a set or not at all. ``remove``: files of an earlier run
    that this one's set replaces by nothing (e.g. ``EST.map3.txt`` after a run with three maps), deleted with it.
    A set opened inside another joins it."""
    outer = _PENDING.get()
    if outer is not None:
        outer["remove"].extend(remove)
        yield
        return
    pending: dict = {"files": [], "remove": list(remove)}
    token = _PENDING.set(pending)
    try:
        yield
        with _signals_held():
            for tmp, dst, is_dir, holder in pending["files"]:
                _publish(tmp, dst, is_dir)
                if holder is not None:
                    shutil.rmtree(holder, ignore_errors=True)
                    _live(holder, False)
            for path in pending["remove"]:
                with contextlib.suppress(FileNotFoundError):
                    Path(path).unlink()
    except BaseException:
        # Also a Ctrl+C between the block's end and the hold: then nothing was renamed yet.
        for tmp, _, _, holder in pending["files"]:
            if tmp.exists() or (holder is not None and holder.exists()):
                _discard(tmp, holder)
        raise
    finally:
        _PENDING.reset(token)


@contextlib.contextmanager
def _signals_held():
    """SIGINT and SIGTERM held off, not ignored: one arriving in the block is acted on when it ends. Python runs signal
    handlers in the main thread only (a mask would not do: the kernel may hand the signal to another thread), so
    elsewhere there is nothing to hold."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    _tell(held=True)
    previous = {sig: signal.signal(sig, lambda signum, frame: caught.append(signum)) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
        _tell(held=False)
        if caught:
            signal.raise_signal(caught[0])


@contextlib.contextmanager
def atomic_path(dst: str | Path, inputs: tuple[str | Path, ...] = (), is_dir: bool = False, same_name: bool = False):
    """Yield a temporary path next to ``dst``; on success rename it onto ``dst``, on error delete it.

    ``inputs`` are files this output must never replace. ``same_name``: the temporary path has ``dst``'s own name,
    inside a temporary folder, and is not created (for writers that name what they write after their path: a ROS2
    bag's storage file and its metadata carried the random temporary name).
    """
    dst = Path(dst)
    _check_not_input(dst, tuple(Path(p) for p in inputs))
    _check_target(dst, is_dir)
    parent = dst.parent if str(dst.parent) else Path(".")
    if not parent.exists():
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(dst, f"cannot create the output folder ({exc.strerror})") from None
    if not os.access(parent, os.W_OK):
        raise OutputError(dst, "output folder is not writable")
    holder = None
    try:
        if same_name:
            holder = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", suffix=".tmp", dir=parent))
            tmp = holder / dst.name
        elif is_dir:
            tmp = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", suffix=".tmp", dir=parent))
        else:
            fd, name = tempfile.mkstemp(prefix=f".{dst.name}.", suffix=".tmp" + dst.suffix, dir=parent)
            os.close(fd)
            tmp = Path(name)
    except OSError as exc:
        # A folder that says it is writable but takes no new file: /proc, a full inode table, a read-only remount.
        raise OutputError(dst, f"cannot create the output ({exc.strerror or exc})") from None
    _live(tmp, True)  # a file written inside a holder first: the watchdog can remove the holder only once empty
    if holder is not None:
        _live(holder, True)
    pending = _PENDING.get()
    try:
        yield tmp
        # mkstemp/mkdtemp create 0600/0700; give the result the permissions a plain open() would.
        os.chmod(tmp, (0o777 if is_dir else 0o666) & ~_umask())
        if pending is not None:
            pending["files"].append((tmp, dst, is_dir, holder))  # renamed with the rest of the set (or deleted with it)
            return
        _publish(tmp, dst, is_dir)
    except BaseException as exc:
        _discard(tmp, holder)
        reason = write_failure(exc)
        if reason is not None:
            raise OutputError(dst, f"cannot write the output ({reason})") from None
        raise
    finally:
        if holder is not None and pending is None:
            shutil.rmtree(holder, ignore_errors=True)
            _live(holder, False)
