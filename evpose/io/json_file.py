"""Reading a small JSON file (layouts, bookmarks) with every way it can fail named in one line."""

from __future__ import annotations

import json
from pathlib import Path

from evpose.errors import InputError


def read_json(path: str | Path) -> object:
    """The parsed content of ``path``; an unreadable file, text that is not UTF-8 or not JSON raises InputError
    naming the file (and the line, for JSON syntax errors); so do a number too long for Python's int and nesting too deep
for its parser."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(path, "not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise InputError(path, f"not valid JSON ({exc.msg})", f"line {exc.lineno}") from None
    except ValueError:
        # A number of more than 4300 digits: Python's int conversion limit raised a bare ValueError (session 29: out
        # of the viewer's start as a traceback, the Bookmarks folder never built).
        raise InputError(path, "not valid JSON (a number of more than 4300 digits)") from None
    except RecursionError:
        # Arrays or objects nested thousands deep: the parser's recursion ran out, a traceback as above.
        raise InputError(path, "not valid JSON (nested too deep)") from None
