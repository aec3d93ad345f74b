"""Checks shared by ``evpose bench`` and ``evpose sweep`` before any job starts."""

from __future__ import annotations

import re
from pathlib import Path

from evpose.errors import ConfigError

# What distributed's Client accepts: an optional scheme, a host, a port.
_ADDRESS = re.compile(r"^(?:(?:tcp|tls|ws|wss|ucx|inproc)://)?[^\s:/]+:\d{1,5}$")


def check_runner_args(workers: int, scheduler: str | None, folders: tuple[Path | None, ...]) -> None:
    """Refuse a negative worker count, a malformed scheduler address and output folders that cannot be created.

    A malformed address made distributed's half-built Client hang 20 s at exit and print a traceback; an
    ``--out`` that is a file ended in a NotADirectoryError traceback once the first job finished.
    """
    from evpose.io.atomic import check_outputs

    if workers < 0:
        raise ConfigError(f"--workers must be >= 0 (0/1: run in this process), got {workers}")
    if scheduler is not None and not _ADDRESS.match(scheduler):
        raise ConfigError(f"--scheduler must be an address like tcp://host:8786, got {scheduler!r}")
    check_outputs((), folders=folders)
