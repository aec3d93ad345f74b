"""Atomic output: write to a temporary sibling, then rename, so no half-written file is ever left."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

from evpose.errors import InputError


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
    if is_dir and dst.exists() and not dst.is_dir():
        raise InputError(dst, "output folder exists and is a file")
    ancestor = dst.parent if str(dst.parent) else Path(".")
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise InputError(dst, f"cannot create the output: {ancestor} is a file, not a folder")
    if not os.access(ancestor, os.W_OK):
        raise InputError(dst, "output folder is not writable")


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
        raise InputError(dst, "output folder is not writable")
    holder = None
    if same_name:
        holder = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", suffix=".tmp", dir=parent))
        tmp = holder / dst.name
    elif is_dir:
        tmp = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", suffix=".tmp", dir=parent))
    else:
        fd, name = tempfile.mkstemp(prefix=f".{dst.name}.", suffix=".tmp" + dst.suffix, dir=parent)
        os.close(fd)
        tmp = Path(name)
    try:
        yield tmp
        # mkstemp/mkdtemp create 0600/0700; give the result the permissions a plain open() would.
        os.chmod(tmp, (0o777 if is_dir else 0o666) & ~_umask())
        if is_dir and dst.exists():
            shutil.rmtree(dst) if dst.is_dir() else dst.unlink()
        os.replace(tmp, dst)
    except BaseException:
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
        raise
    finally:
        if holder is not None:
            shutil.rmtree(holder, ignore_errors=True)
