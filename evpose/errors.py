"""Exception types shared by every layer.

Every error a user can cause with bad input is an :class:`EvposeError`; the CLI
prints its one-line message and exits with code 2. Modules derive their own
subclass so callers can tell the source apart (evo's "one exception type per
module" rule), but all of them print the same way.
"""

from __future__ import annotations

from pathlib import Path


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
        parts = [p for p in (self.path, record, problem) if p]
        super().__init__(": ".join(parts))


class OutputError(InputError):
    """An output that cannot be written: a full disk, a read-only or vanished folder, a path where no file can be
    created. Printed like an :class:`InputError` (``<file>: <problem>``, exit code 2): the user's remedy is another
    ``--out`` or some free space, and a traceback (or, from HDF5, a crash at exit) helps no one."""


class ConfigError(EvposeError):
    """An invalid configuration value or combination of options."""
