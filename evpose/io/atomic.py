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
    for src in inputs:
        try:
            if src.exists() and dst.exists() and os.path.samefile(src, dst):
                raise InputError(dst, "refusing to overwrite an input file")
        except OSError:
            continue


@contextlib.contextmanager
def atomic_path(dst: str | Path, inputs: tuple[str | Path, ...] = (), is_dir: bool = False):
    """Yield a temporary path next to ``dst``; on success rename it onto ``dst``, on error delete it.

    ``inputs`` are files this output must never replace.
    """
    dst = Path(dst)
    _check_not_input(dst, tuple(Path(p) for p in inputs))
    parent = dst.parent if str(dst.parent) else Path(".")
    if not parent.exists():
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(dst, f"cannot create the output folder ({exc.strerror})") from None
    if not os.access(parent, os.W_OK):
        raise InputError(dst, "output folder is not writable")
    if is_dir:
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
