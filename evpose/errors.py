"""Exception types shared by every layer.

Every error a user can cause with bad input is an :class:`EvposeError`; the CLI
prints its one-line message and exits with code 2. Modules derive their own
subclass so callers can tell the source apart (evo's "one exception type per
module" rule), but all of them print the same way.
"""

from __future__ import annotations

from pathlib import Path


def printable(text: str) -> str:
    """``text`` with control characters (newline, tab, escape, undecodable bytes of a file name) written as escapes, as
    in a Python string literal: a file name holding a newline split the one-line message in two, and one holding an
    escape sequence drove the terminal."""
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape", "backslashreplace").decode("ascii") for ch in text)


def one_line(text: str) -> str:
    """A message on one line: line breaks (a library's multi-line report quoted in a problem) become spaces, other
    control characters escapes."""
    return printable(" ".join(text.splitlines()))


RAISED_INTERRUPTS: list[KeyboardInterrupt] = []
"""The interrupts (Ctrl+C, SIGTERM) the CLI's signal handlers raised in the current command (``evpose.cli.main``): C
code may swallow one and fail otherwise (pybind11's "ImportError: initialization failed")."""


def interrupt_cause(exc: BaseException | None, swallowed: bool = False) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl+C, or SIGTERM raised as one) that ``exc`` was raised from, if any; ``swallowed``:
    else the last one raised in this command at all (C code that swallowed it then failed). Code that turns a failure
    into a message (a missing optional library, a fallback) re-raises this instead: the user asked to stop."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, KeyboardInterrupt):
            return exc
        exc = exc.__cause__ or exc.__context__
    return RAISED_INTERRUPTS[-1] if swallowed and RAISED_INTERRUPTS else None


class EvposeError(Exception):
    """Base class of errors caused by input or configuration, reported without traceback."""


class InputError(EvposeError):
    """A problem in an input file, located as precisely as we can.

    The message always reads ``<file>: <record>: <problem>`` (the record part is
    omitted when the whole file is at fault), so a user can go straight to it.
    """

    def __init__(self, path: str | Path | None, problem: str, record: str | None = None):
        self.path = None if path is None else str(path)
        self.record = record
        self.problem = problem
        parts = [p for p in (None if self.path is None else printable(self.path), record, problem) if p]
        super().__init__(one_line(": ".join(parts)))


class OutputError(InputError):
    """An output that cannot be written: a full disk, a read-only or vanished folder, a path where no file can be
    created. Printed like an :class:`InputError` (``<file>: <problem>``, exit code 2): the user's remedy is another
    ``--out`` or some free space, and a traceback (or, from HDF5, a crash at exit) helps no one."""


class ConfigError(EvposeError):
    """An invalid configuration value or combination of options."""
