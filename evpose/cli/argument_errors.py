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
        # Where stderr cannot encode the box (an ASCII locale), rich draws the title, a rule of "-", the text and
        # another rule: both rules and the help hint were printed in the one line.
        if not inner.strip("─-"):
            if inner and body:  # a rule after the text: the problem's section has ended
                break
            continue
        body.append(inner)
    message = _plain_optional(re.sub(r"\s+", " ", " ".join(body)).strip())
    return message or title or "invalid arguments"


_OPTIONAL = re.compile(r"^(Error parsing \S+): no type matching \{None\}\|(\w+) could be instantiated from \[(.*?)\]\. Got errors: .*$")
_KINDS = {"INT": "an integer", "FLOAT": "a number", "PATH": "a path", "STR": "a text"}


def _plain_optional(message: str) -> str:
    """tyro's error for an optional flag (``int | None``) given a bad value lists each type's failure, Python class names
    and all ("no type matching {None}|INT could be instantiated from ['abc']. Got errors: - <class 'NoneType'>: ...");
    what it means is the flag's kind and the value (session 32: ``track --smoothed-lag abc``)."""
    m = _OPTIONAL.match(message)
    if m is None:
        return message
    return f"{m.group(1)}: expected {_KINDS.get(m.group(2), m.group(2))}, got {m.group(3)}"


def _refuse_empty(args: list[str]) -> None:
    """An empty argument (``--out ""``, ``--out=``, a positional ``""``) is refused: tyro reads it as the path ``.``, so
    ``bench --out ""`` wrote its report, jobs and data into the current folder (session 32's fuzzing)."""
    for i, arg in enumerate(args):
        if arg.startswith("--") and arg.endswith("=") and len(arg) > 3:
            raise ArgumentError(f"{arg[:-1]}: empty value; give one (see the command's --help)")
        if arg == "" or not arg.strip():
            before = args[i - 1] if i > 0 else ""
            where = before.split("=", 1)[0] if before.startswith("--") and "=" not in before else f"argument {i + 1}"
            raise ArgumentError(f"{where}: empty value; give one (see the command's --help)")


def run_tyro(main: Callable[..., Any], args: list[str], prog: str) -> Any:
    """``tyro.cli(main, args=args, prog=prog)``, raising :class:`ArgumentError` (one line) where tyro would print its
    panel and exit 2. ``--help`` and everything ``main`` prints are untouched."""
    import tyro

    _refuse_empty(args)
    real_stderr = sys.stderr
    captured = io.StringIO()

    def restore() -> str:
        """Ends the capture (once); what tyro wrote meanwhile."""
        if sys.stderr is captured:
            sys.stderr = real_stderr
            return captured.getvalue()
        return ""

    @functools.wraps(main)
    def parsed(*a, **k):
        # tyro calls this only once every argument parsed: from here on the command's own messages are real.
        real_stderr.write(restore())
        return main(*a, **k)

    sys.stderr = captured
    try:
        return tyro.cli(parsed, args=args, prog=prog)
    except SystemExit as exc:
        text = restore()  # empty when the command itself exited: parsing had ended
        if exc.code == 2 and text:
            raise ArgumentError(f"{flatten_panel(text)} (see {prog} --help)") from None
        real_stderr.write(text)
        raise
    finally:
        real_stderr.write(restore())  # a Ctrl+C while tyro parses
