"""Command-line argument errors as one line, like every other input error.

tyro reports a bad flag (an unknown choice, a value of the wrong type, a missing argument) as a boxed panel of 5-15
lines on stderr and exits 2. The project's rule is one line naming the problem, so the panel is captured while tyro
parses and flattened: its title and first section (what is wrong), without the help text and the box. Whatever the
command itself prints goes to the real stderr, since the capture ends the moment tyro calls the command.
"""

from __future__ import annotations

import functools
import io
import re
import sys
from typing import Any, Callable

from evpose.errors import ConfigError

_BORDER = "╭╮╰╯│─"


class ArgumentError(ConfigError):
    """A command-line argument tyro refused (exit code 2, one line)."""


def flatten_panel(text: str) -> str:
    """The problem a tyro error panel states, on one line: its first section (the help text and the "For full
    helptext" hint after the first rule are left out; the title, e.g. "Invalid choice", only when that is empty)."""
    lines = text.strip().splitlines()
    if not lines:
        return "invalid arguments"
    title = lines[0].strip(_BORDER + " ")
    body: list[str] = []
    for line in lines[1:]:
        inner = line.strip().strip("│").strip()
        if not inner.strip("─"):
            if inner:  # a rule: the problem's section has ended
                break
            continue
        body.append(inner)
    message = re.sub(r"\s+", " ", " ".join(body)).strip()
    return message or title or "invalid arguments"


def run_tyro(main: Callable[..., Any], args: list[str], prog: str) -> Any:
    """``tyro.cli(main, args=args, prog=prog)``, raising :class:`ArgumentError` (one line) where tyro would print its
    panel and exit 2. ``--help`` and everything ``main`` prints are untouched."""
    import tyro

    real_stderr = sys.stderr
    captured = io.StringIO()

    @functools.wraps(main)
    def parsed(*a, **k):
        # tyro calls this only once every argument parsed: from here on the command's own messages are real.
        sys.stderr = real_stderr
        return main(*a, **k)

    sys.stderr = captured
    try:
        return tyro.cli(parsed, args=args, prog=prog)
    except SystemExit as exc:
        if sys.stderr is captured and exc.code == 2:
            raise ArgumentError(f"{flatten_panel(captured.getvalue())} (see {prog} --help)") from None
        raise
    finally:
        if sys.stderr is captured:
            sys.stderr = real_stderr
            if captured.getvalue() and sys.exc_info()[0] is None:
                real_stderr.write(captured.getvalue())
