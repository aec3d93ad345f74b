"""The Bookmarks folder of the left panel: save the moment on screen under a title, list the saved ones, go back to one.

Going to a bookmark applies its layout first (which sets the layout's own stage), then opens its recording, map and
viewer mode if another is shown, seeks exactly to its time and sets its stage. Exactly: not to the kept frame at or
before it, as the time slider may (app/player_config.py ``snap_seeks``); snapping, the browser test's bookmark at
step 33 came back at step 32. The file and its format are app/bookmarks.py. A notice line under the controls says
what happened; a bookmark file that cannot be read is named there with its problem (the folder opens and its title
says so), and saving or editing is refused until it is mended: it is never written over.

Session 29 added what a teacher preparing a lesson expects: rename (the chosen bookmark takes the title typed above),
move up / down (the list is the lesson's order) and delete behind a confirmation: one click on "delete", next to "go
to", removed a bookmark for good; now a red "yes, delete" and a "no, keep it" come up under the list and the notice
line names the bookmark, and choosing another bookmark or any other action first keeps it. "reload" reads the file
again: one mended (or edited) by hand was read only at the next save or a restart.

Session 28 on the bundled demo (/tmp/s28/ux28b/demo_check.py, disk cache warm): a bookmark at 3.000 s of landing
(step 593, polarity stage, teaching layout) saved, indoor opened, then "go to": landing, step 593 at 3.000 s, the
stage and layout back within 0.5 s.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import TYPE_CHECKING

from app.bookmarks import Bookmark, add_bookmark, check_title, load_bookmarks, move_bookmark, remove_bookmark, rename_bookmark
from app.layouts import Layout
from evpose.errors import EvposeError, InputError

if TYPE_CHECKING:
    from app.server import ViewerApp

NONE_SAVED = "(no bookmarks yet)"
HINTS = {
    "title": "A short title for the moment on screen, as the list below shows it (rename: the chosen bookmark's new title)",
    "save": "Keep the moment on screen (recording, map, viewer mode, step, teaching stage, layout) under the title "
            "above, in the bookmarks file",
    "list": "The saved moments of the lesson; choosing one goes there",
    "actions": "go to: the chosen bookmark again (its layout, recording, step and stage); rename: give it the title "
               "typed above; delete: remove it from the file (asks first)",
    "order": "Move the chosen bookmark up or down the list (a lesson's bookmarks in the order they are to be shown); "
             "reload: read the file again (after mending or editing it by hand)",
    "confirm": "Remove the bookmark named below from the file for good",
    "keep": "Keep the bookmark: nothing is deleted",
}
"""Hover text of the folder's controls."""


def _shown(path) -> str:
    """A file as the notice line names it: from the current folder when inside it (an absolute path has no break in
    it and ran past the panel's edge; ``layouts/bookmarks/bookmarks.json`` fits)."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def _located(exc: Exception) -> str:
    """An error for the notice line, its file as code (:func:`_shown`)."""
    path, text = getattr(exc, "path", None), str(exc)
    return f"`{_shown(path)}`{text[len(path):]}" if path and text.startswith(path) else text


class BookmarkGui:
    """The Bookmarks folder's controls, wired to a :class:`ViewerApp`, and the bookmarks as last read."""

    def __init__(self, app: ViewerApp, path: Path, folder=None):
        g = app.gui
        self.app = app
        self.folder = folder
        """The folder holding the controls: opened, and its title saying so, when the file cannot be read."""
        self.path = Path(path)
        self.bookmarks: list[Bookmark] = []
        self._file_lock = threading.Lock()
        """Two tabs saving at once would each read the file, add theirs and write: one bookmark would be lost."""
        self.title_box = g.add_text("bookmark title", "", hint=HINTS["title"])
        self.save_button = g.add_button("save this moment", hint=HINTS["save"])
        self.dropdown = g.add_dropdown("bookmarks", [NONE_SAVED], hint=HINTS["list"])
        self.actions = g.add_button_group("bookmark", ["go to", "rename", "delete"], hint=HINTS["actions"])
        self.order = g.add_button_group("list", ["move up", "move down", "reload"], hint=HINTS["order"])
        # Shown only while a deletion waits to be confirmed (ask_delete).
        self.confirm_button = g.add_button("yes, delete", color="red", visible=False, hint=HINTS["confirm"])
        self.keep_button = g.add_button("no, keep it", visible=False, hint=HINTS["keep"])
        self.note = g.add_markdown("")
        self.to_delete: Bookmark | None = None
        """The bookmark a deletion waits to be confirmed for (None: none)."""
        self.save_button.on_click(lambda e: self._cancel_delete() or self.save(self.title_box.value))
        # A choice made in the browser goes there; the options rewritten here must not.
        self.dropdown.on_update(lambda e: e.client is not None and (self._cancel_delete() or self.go_to(self.chosen())))
        self.actions.on_click(lambda e: self._action(e.target.value))
        self.order.on_click(lambda e: self._action(e.target.value))
        self.confirm_button.on_click(lambda e: self.delete(self.to_delete))
        self.keep_button.on_click(lambda e: self._cancel_delete(say=True))
        self.reload()

    # ------------------------------------------------------------------ the list
    def reload(self, say: bool = False) -> bool:
        """Read the file again; an unreadable one is named in the notice line, the list emptied. ``say``: say what was
        read (the "reload" button: a file mended by hand was read only at the next save, or a restart)."""
        try:
            self._show(load_bookmarks(self.path))
        except EvposeError as exc:
            self._show([])
            self._say(f"**bookmarks not read:** {_located(exc)} (fix or move the file, then press reload; nothing is "
                      "saved to it until then)")
            self._mark_file(False)
            return False
        self._mark_file(True)
        if say:
            self._say(f"read {len(self.bookmarks)} bookmark{'s' * (len(self.bookmarks) != 1)} from `{_shown(self.path)}`")
        return True

    def _mark_file(self, readable: bool) -> None:
        """Title the folder by whether the file could be read; an unreadable one opens it (closed, as it starts, nobody
        saw the notice in it)."""
        if self.folder is None:
            return
        self.folder.label = "Bookmarks" if readable else "Bookmarks: file not read"
        if not readable:
            self.folder.expand_by_default = True

    def _show(self, bookmarks: list[Bookmark], chosen: int | None = None) -> None:
        self.bookmarks = list(bookmarks)
        labels = [b.label(i + 1) for i, b in enumerate(self.bookmarks)] or [NONE_SAVED]
        self.dropdown.options = labels
        self.dropdown.value = labels[chosen if chosen is not None and 0 <= chosen < len(labels) else 0]

    def chosen(self) -> Bookmark | None:
        """The bookmark the dropdown shows (None when there is none)."""
        labels = [b.label(i + 1) for i, b in enumerate(self.bookmarks)]
        return self.bookmarks[labels.index(self.dropdown.value)] if self.dropdown.value in labels else None

    def _say(self, text: str) -> None:
        self.note.content = text

    def _refused(self, what: str, exc: Exception) -> None:
        """Say why an edit was refused, and list the file as it is now when it can be read: a bookmark deleted by hand
        or by another viewer stayed listed, and every edit of it was refused again ("not in the file any more")."""
        try:
            with self._file_lock:
                self._show(load_bookmarks(self.path))
        except EvposeError:
            pass  # unreadable: the list stays as it was, the message says why
        self._say(f"**{what}:** {_located(exc)}")

    # ------------------------------------------------------------------ actions
    def current(self, title: str) -> Bookmark:
        """The moment on screen as a bookmark titled ``title``."""
        app, frame = self.app, self.app.last_frame
        if frame is None or app.player is None or app._open_displays is None:
            raise InputError(None, "nothing is shown yet: open a recording and wait for its first step")
        from app.viewer_controls import NO_MAP

        rec, cmap = app._open_displays
        return Bookmark(check_title(title), rec, None if cmap == NO_MAP else cmap, app.mode,
                        max(0, int(frame.t_us - app.player.engine.t_start_us)), int(frame.index), app.stage.value,
                        app.layout.name if app.layout is not None else "debug")

    def save(self, title: str) -> Bookmark | None:
        try:
            bookmark = self.current(title)
            with self._file_lock:
                bookmarks = add_bookmark(bookmark, self.path)
        except (EvposeError, OSError) as exc:  # OSError: a file name too long, no permission
            self._say(f"**not saved:** {_located(exc)}")
            return None
        self._show(bookmarks, len(bookmarks) - 1)
        self._mark_file(True)  # read and written: mended if it was not
        self._say(f"saved {bookmark.label(len(bookmarks))} to `{_shown(self.path)}`")
        return bookmark

    def _action(self, action: str) -> None:
        """A button of the "bookmark" or "list" group; any but "delete" gives up a deletion waiting to be confirmed."""
        if action == "delete":
            self.ask_delete(self.chosen())
            return
        self._cancel_delete()
        if action == "go to":
            self.go_to(self.chosen())
        elif action == "rename":
            self.rename(self.chosen(), self.title_box.value)
        elif action in ("move up", "move down"):
            self.move(self.chosen(), -1 if action == "move up" else 1)
        elif action == "reload":
            self.reload(say=True)

    def ask_delete(self, bookmark: Bookmark | None) -> bool:
        """Ask before deleting ``bookmark``: the confirmation buttons come up and the notice line names it."""
        if bookmark is None:
            self._say("**nothing to delete:** no bookmark is chosen")
            return False
        self.to_delete = bookmark
        self.confirm_button.visible = self.keep_button.visible = True
        self._say(f"**delete {bookmark.label(self.bookmarks.index(bookmark) + 1)}?** It is removed from the file for "
                  "good: press \"yes, delete\" or \"no, keep it\" (above).")
        return True

    def _cancel_delete(self, say: bool = False) -> None:
        """Give up a deletion waiting to be confirmed (the bookmark stays); ``say``: tell so in the notice line."""
        if self.to_delete is not None and say:
            self._say(f"kept {self.to_delete.title!r}")
        self.to_delete = None
        if self.confirm_button.visible:
            self.confirm_button.visible = self.keep_button.visible = False

    def delete(self, bookmark: Bookmark | None) -> bool:
        """Delete ``bookmark`` from the file now (the "yes, delete" button; "delete" asks first: :meth:`ask_delete`)."""
        self._cancel_delete()
        if bookmark is None:
            return False
        try:
            with self._file_lock:
                bookmarks = remove_bookmark(bookmark, self.path)
        except (EvposeError, OSError) as exc:  # OSError: a file name too long, no permission
            self._refused("not deleted", exc)
            return False
        self._show(bookmarks)
        self._mark_file(True)
        self._say(f"deleted {bookmark.title!r}")
        return True

    def rename(self, bookmark: Bookmark | None, title: str) -> bool:
        """Give ``bookmark`` the title ``title`` in the file."""
        return self._edit(bookmark, "rename", "renamed", lambda: rename_bookmark(bookmark, title, self.path),
                          lambda bookmarks, index: f"renamed {bookmark.title!r} to {bookmarks[index].title!r}")

    def move(self, bookmark: Bookmark | None, delta: int) -> bool:
        """Move ``bookmark`` ``delta`` places on in the list (-1 up, +1 down); it stays chosen."""
        return self._edit(bookmark, "move", "moved", lambda: move_bookmark(bookmark, delta, self.path),
                          lambda bookmarks, index: f"{bookmark.title!r} is number {index + 1} of {len(bookmarks)}")

    def _edit(self, bookmark: Bookmark | None, verb: str, done: str, edit, said) -> bool:
        """Run ``edit()`` (the file's bookmarks after it and the edited one's index) under the file lock, show the
        result with that bookmark chosen and say ``said(bookmarks, index)``; a refusal is said in one line."""
        if bookmark is None:
            self._say(f"**nothing to {verb}:** no bookmark is chosen")
            return False
        try:
            with self._file_lock:
                bookmarks, index = edit()
        except (EvposeError, OSError) as exc:  # OSError: a file name too long, no permission
            self._refused(f"not {done}", exc)
            return False
        self._show(bookmarks, index)
        self._mark_file(True)
        self._say(said(bookmarks, index))
        return True

    def go_to(self, bookmark: Bookmark | None) -> bool:
        """Show ``bookmark``'s moment: layout, recording (map, mode), exact time, stage. A recording or map that is gone
        is said and nothing changes (not its layout alone); a layout that is gone is said and the current one kept."""
        from app.viewer_controls import NO_MAP  # not at the top: that module builds this one

        app = self.app
        if bookmark is None:
            return False
        rec = app._entry(bookmark.recording)
        map_display = NO_MAP if bookmark.map is None else bookmark.map
        gone = (f"recording `{bookmark.recording}`" if rec is None else
                f"map `{bookmark.map}`" if map_display != NO_MAP and app._entry(map_display) is None else "")
        if gone:
            self._say(f"**cannot go to {bookmark.title!r}:** {gone} is not under the data folders")
            return False
        layout = app.layout_gui.available().get(bookmark.layout)
        if isinstance(layout, Layout):
            app.apply_layout(layout)
            missing = ""
        else:  # apply_layout_name would put up the debug layout instead, which was not asked for
            missing = f"; layout `{bookmark.layout}` not found, kept `{app.layout.name if app.layout else '?'}`"
        if app.player is None or app._open_displays != (rec.display, map_display) or app.mode != bookmark.mode:
            mode, app.mode_dropdown.value = app.mode, bookmark.mode  # select() opens in the mode the dropdown names
            if not app.select(rec.display, map_display):
                app.mode_dropdown.value = mode
                self._say(f"**cannot go to {bookmark.title!r}:** its recording did not open (see above){missing}")
                return False
        player, t_us = app.player, bookmark.t_us
        player.pause()  # the moment is to be looked at: playing on from it, it was gone at once
        # On the player's thread, after the opening queued above: the time is from the start of the engine then loaded.
        player.call(lambda engine: player.seek(engine.t_start_us + t_us, exact=True))
        app.stage_dropdown.value = bookmark.stage
        self._say(f"went to {bookmark.title!r}: `{bookmark.recording}` at {t_us / 1e6:.3f} s (step {bookmark.step}), "
                  f"stage {bookmark.stage}{missing}")
        return True
