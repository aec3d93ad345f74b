"""Lesson bookmarks: a named moment of a lesson (recording, map, viewer mode, step, teaching stage, layout) and the
JSON file that keeps them; no viser here (the Bookmarks folder is app/bookmark_gui.py).

A teacher asked to save the moment on screen and come back to it in class (session 28). The file is
``<layout folder>/bookmarks/bookmarks.json`` by default (``evpose app --bookmarks FILE``: another), beside the layouts a lesson
uses but in a folder of its own: in ``layouts/`` itself it was listed as a broken layout named "bookmarks", and saving
a layout of that name would have replaced it. Its form::

    {"bookmarks": [{"title": "the TDF valleys", "recording": "demo_data/landing.h5", "map": "maps/landing_map.ply",
                    "mode": "tracking", "t_us": 1250000, "step": 124, "stage": "TDF", "layout": "teaching"}]}

``t_us`` is microseconds from the recording's start (the time slider's origin), the time a jump seeks to exactly;
``step`` is the step index shown then (a check, not used to seek: the same time is the same step unless the
parameters changed). ``map`` null means "no map". Every write replaces the whole file atomically
(evpose/io/atomic.py); a file that cannot be read is refused with one line naming it and the problem, and is never
written over (:func:`add_bookmark`, :func:`remove_bookmark`, :func:`rename_bookmark` and :func:`move_bookmark` read
the file again before writing, so edits made meanwhile by hand or by another viewer are kept). A bookmarks file that is
a symbolic link (a lesson's file kept elsewhere, linked in) is written where it points: replaced by the atomic rename,
the link became a copy and the lesson's own file silently stopped getting the new bookmarks.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from app.engine_factory import MODES
from app.teaching import Stage
from evpose.errors import InputError
from evpose.io.json_file import read_json

BOOKMARKS_NAME = Path("bookmarks") / "bookmarks.json"
"""Where the bookmarks are kept, relative to the layout folder (see the module docstring for why not in it)."""
MAX_TITLE = 80
"""Longest title, characters (it is shown in a dropdown)."""
FIELDS = ("title", "recording", "map", "mode", "t_us", "step", "stage", "layout")


@dataclass(frozen=True)
class Bookmark:
    """One saved moment of a lesson."""

    title: str
    recording: str
    """The recording's label as the recording dropdown shows it (data folder name / path inside it)."""
    map: str | None
    """The map's label, None for no map."""
    mode: str
    """The viewer mode, one of app.engine_factory.MODES."""
    t_us: int
    """Time from the recording's start, microseconds (the step shown then is the last at or before it)."""
    step: int
    """Index of the step shown when it was saved."""
    stage: str
    """The teaching panel's stage (an app.teaching.Stage value)."""
    layout: str
    """The layout's name."""

    def label(self, number: int) -> str:
        """How the bookmarks dropdown lists it (numbered: two bookmarks may share a title)."""
        return f"{number}. {self.title} ({self.recording.rsplit('/', 1)[-1]}, {self.t_us / 1e6:.3f} s, {self.stage})"

    @classmethod
    def from_dict(cls, data, source: str | None = None, key: str = "bookmark") -> "Bookmark":
        """Check one parsed bookmark; a problem names its key (``bookmarks[2].stage``)."""
        if not isinstance(data, dict):
            raise InputError(source, "must be an object", key)
        unknown = sorted(set(data) - set(FIELDS))
        if unknown:
            raise InputError(source, f"unknown key (known: {', '.join(FIELDS)})", f"{key}.{unknown[0]}")
        missing = [f for f in FIELDS if f not in data]
        if missing:
            raise InputError(source, "missing key", f"{key}.{missing[0]}")
        for name in ("title", "recording", "mode", "stage", "layout"):
            if not isinstance(data[name], str) or not data[name].strip():
                raise InputError(source, "must be a non-empty string", f"{key}.{name}")
        if data["map"] is not None and (not isinstance(data["map"], str) or not data["map"]):
            raise InputError(source, "must be a non-empty string or null", f"{key}.map")
        for name in ("t_us", "step"):
            if isinstance(data[name], bool) or not isinstance(data[name], int) or data[name] < 0:
                raise InputError(source, f"must be a whole number >= 0, got {data[name]!r}", f"{key}.{name}")
        if len(data["title"]) > MAX_TITLE:
            raise InputError(source, f"longer than {MAX_TITLE} characters", f"{key}.title")
        if data["mode"] not in MODES:
            raise InputError(source, f"{data['mode']!r} is none of {', '.join(MODES)}", f"{key}.mode")
        if data["stage"] not in {s.value for s in Stage}:
            raise InputError(source, f"{data['stage']!r} is none of {', '.join(s.value for s in Stage)}", f"{key}.stage")
        return cls(**{f: data[f] for f in FIELDS})


def check_title(title: str) -> str:
    """A title as typed, stripped; empty or too long is refused."""
    title = " ".join(str(title).split())  # one line: a newline pasted into the box would break the dropdown's label
    if not title:
        raise InputError(None, "type a title for the bookmark first")
    if len(title) > MAX_TITLE:
        raise InputError(None, f"a bookmark title is at most {MAX_TITLE} characters, got {len(title)}")
    return title


def load_bookmarks(path: str | Path) -> list[Bookmark]:
    """The bookmarks in ``path`` (none if it does not exist); a file that cannot be read or checked raises InputError
    naming the file and the problem."""
    path = Path(path)
    if not path.exists():
        return []
    data = read_json(path)
    if not isinstance(data, dict) or set(data) != {"bookmarks"} or not isinstance(data["bookmarks"], list):
        raise InputError(path, 'must be an object with one key, "bookmarks", a list')
    return [Bookmark.from_dict(b, str(path), f"bookmarks[{i}]") for i, b in enumerate(data["bookmarks"])]


def save_bookmarks(bookmarks: list[Bookmark], path: str | Path) -> Path:
    """Write ``bookmarks`` to ``path`` atomically (a crash or a full disk leaves the previous file whole)."""
    from evpose.io.atomic import atomic_path

    path = Path(path)
    if path.is_symlink():
        path = path.resolve()  # the file it points at, not a copy in its place (module docstring)
    text = json.dumps({"bookmarks": [dataclasses.asdict(b) for b in bookmarks]}, indent=2, ensure_ascii=False) + "\n"
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return path


def add_bookmark(bookmark: Bookmark, path: str | Path) -> list[Bookmark]:
    """Append ``bookmark`` to the file as it is now (edits made by hand or by another viewer are kept) and return the
    list written; an unreadable file raises InputError and is left as it is."""
    bookmarks = load_bookmarks(path) + [bookmark]
    save_bookmarks(bookmarks, path)
    return bookmarks


def _edit(bookmark: Bookmark, path: str | Path, change) -> tuple[list[Bookmark], int]:
    """Apply ``change(bookmarks, i)`` (which returns the edited bookmark's new index) to the file as it is now, where
    ``bookmark`` is at ``i``, and write it; the list written and that index. A bookmark no longer in the file (edited
    by hand or by another viewer meanwhile) is refused, never guessed at."""
    bookmarks = load_bookmarks(path)
    if bookmark not in bookmarks:
        raise InputError(path, f"no bookmark {bookmark.title!r} in the file any more (changed meanwhile?)")
    index = change(bookmarks, bookmarks.index(bookmark))
    save_bookmarks(bookmarks, path)
    return bookmarks, index


def remove_bookmark(bookmark: Bookmark, path: str | Path) -> list[Bookmark]:
    """Remove the first bookmark equal to ``bookmark`` from the file as it is now and return the list written."""

    def remove(bookmarks, i):
        del bookmarks[i]
        return min(i, len(bookmarks) - 1)  # the one after it, which takes its place in the list

    return _edit(bookmark, path, remove)[0]


def rename_bookmark(bookmark: Bookmark, title: str, path: str | Path) -> tuple[list[Bookmark], int]:
    """Give ``bookmark`` the title ``title`` (checked as :func:`check_title` does) in the file as it is now; the list
    written and its index."""
    title = check_title(title)

    def rename(bookmarks, i):
        bookmarks[i] = dataclasses.replace(bookmarks[i], title=title)
        return i

    return _edit(bookmark, path, rename)


def move_bookmark(bookmark: Bookmark, delta: int, path: str | Path) -> tuple[list[Bookmark], int]:
    """Move ``bookmark`` ``delta`` places on in the file's order (-1: up, +1: down; it stops at either end); the list
    written and its new index. A lesson's bookmarks are listed in the order they are to be shown."""

    def move(bookmarks, i):
        j = min(max(i + delta, 0), len(bookmarks) - 1)
        bookmarks.insert(j, bookmarks.pop(i))
        return j

    return _edit(bookmark, path, move)
