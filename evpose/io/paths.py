"""What is wrong with a path that should be a readable file, in the words every reader uses."""

from __future__ import annotations

from pathlib import Path


def not_a_file(path: str | Path) -> str:
    """The problem with ``path`` when ``path.is_file()`` is False: a folder, a pipe / device / socket (a named pipe
    was called "no such file"), or nothing at all."""
    path = Path(path)
    if path.is_dir():
        return "is a folder, not a file"
    if path.exists():
        return "is not a regular file (a pipe, device or socket)"
    return "no such file"
