"""The Bookmarks folder without a browser: a malformed bookmarks file is named in one line and never written over, and
what a bookmark names that is gone is said (a recording or map: nothing changes; a layout: the rest comes back); delete
asks first, rename and move keep the bookmark chosen, and an edit of a bookmark gone from the file lists the file as it is."""

import dataclasses
import socket

from app.bookmarks import Bookmark, load_bookmarks, save_bookmarks
from app.server import AppConfig, ViewerApp


def _viewer(tmp_path, data_root=None):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    if data_root is None:
        data_root = tmp_path / "data"
        data_root.mkdir()
    return ViewerApp(AppConfig(data=[data_root], port=port, layout_dir=tmp_path / "layouts", export_dir=tmp_path / "exports"))


def test_a_malformed_bookmarks_file_is_named_in_one_line_and_saving_leaves_it_as_it_was(tmp_path, monkeypatch):
    path = tmp_path / "layouts" / "bookmarks" / "bookmarks.json"
    path.parent.mkdir(parents=True)
    path.write_text('{"bookmarks": [{"title": "x"}')
    app = _viewer(tmp_path)
    try:
        note = app.bookmark_gui.note.content
        assert str(path) in note and "not valid JSON" in note and "\n" not in note
        assert app.bookmark_gui.dropdown.options == ("(no bookmarks yet)",)
        assert app.bookmark_gui.folder.label == "Bookmarks: file not read" and app.bookmark_gui.folder.expand_by_default
        assert app.bookmark_gui.save("a title") is None
        assert "not saved:** nothing is shown yet" in app.bookmark_gui.note.content
        # As if a moment were shown: the file is read again before it is written, and refused.
        monkeypatch.setattr(app.bookmark_gui, "current", lambda title: Bookmark(title, "data/x.h5", None, "tracking", 0, 0, "events", "debug"))
        assert app.bookmark_gui.save("a title") is None
        assert "not saved" in app.bookmark_gui.note.content and "not valid JSON" in app.bookmark_gui.note.content
        assert path.read_text() == '{"bookmarks": [{"title": "x"}'
        path.write_text('{"bookmarks": []}')  # mended: "reload" reads it, and the next save goes in
        assert app.bookmark_gui.reload(say=True) and app.bookmark_gui.folder.label == "Bookmarks"
        assert app.bookmark_gui.note.content == f"read 0 bookmarks from `{path}`"
        assert app.bookmark_gui.save("a title") is not None and len(app.bookmark_gui.dropdown.options) == 1
        assert app.bookmark_gui.dropdown.value.startswith("1. a title") and app.bookmark_gui.folder.label == "Bookmarks"
    finally:
        app.stop()


def test_going_to_a_bookmark_whose_recording_is_gone_says_so(tmp_path, squares_scene):
    from app_scenes import write_data_root

    root = tmp_path / "data"
    root.mkdir()
    write_data_root(root, squares_scene)
    mark = Bookmark("gone", "data/nowhere.h5", None, "tracking", 100_000, 3, "TDF", "nosuch")
    save_bookmarks([mark, dataclasses.replace(mark, title="map gone", recording="data/bar.h5", map="data/none_map.ply")],
                   tmp_path / "layouts" / "bookmarks" / "bookmarks.json")
    app = _viewer(tmp_path, root)
    try:
        gui, viewer_layout = app.bookmark_gui, app.layout.name
        assert [b.title for b in gui.bookmarks] == ["gone", "map gone"]
        assert not gui.go_to(gui.bookmarks[0])
        assert "recording `data/nowhere.h5` is not under the data folders" in gui.note.content
        assert viewer_layout == app.layout.name  # nothing changed, not the layout alone
        assert not gui.go_to(gui.bookmarks[1]) and "map `data/none_map.ply`" in gui.note.content
        # A layout that is gone: the rest of the moment still comes back, in the layout shown.
        assert gui.go_to(dataclasses.replace(mark, recording="data/bar.h5"))
        assert "layout `nosuch` not found, kept `debug`" in gui.note.content and app.stage.value == "TDF"
    finally:
        app.stop()


def _two_bookmarks(tmp_path):
    """The bookmarks file of a viewer on ``tmp_path`` holding "first" and "second"; (its path, the two)."""
    path = tmp_path / "layouts" / "bookmarks" / "bookmarks.json"
    a, b = (Bookmark(t, "data/x.h5", None, "tracking", 0, 0, "events", "debug") for t in ("first", "second"))
    save_bookmarks([a, b], path)
    return path, a, b


def test_delete_asks_first_and_rename_and_move_keep_the_bookmark_chosen(tmp_path):
    path, a, b = _two_bookmarks(tmp_path)
    app = _viewer(tmp_path)
    try:
        gui = app.bookmark_gui
        gui.dropdown.value = gui.dropdown.options[1]
        gui._action("delete")  # one click removed it for good (session 28): now it asks
        assert gui.to_delete == b and gui.confirm_button.visible and gui.keep_button.visible
        assert "delete 2. second" in gui.note.content and load_bookmarks(path) == [a, b]
        gui._cancel_delete(say=True)  # "no, keep it"
        assert not gui.confirm_button.visible and gui.note.content == "kept 'second'" and load_bookmarks(path) == [a, b]
        gui._action("delete")
        gui._action("go to")  # any other action first keeps it too
        assert gui.to_delete is None and not gui.confirm_button.visible and load_bookmarks(path) == [a, b]

        gui.title_box.value = "the second, renamed"
        gui._action("rename")
        renamed = dataclasses.replace(b, title="the second, renamed")
        assert load_bookmarks(path) == [a, renamed] and gui.chosen() == renamed
        assert gui.note.content == "renamed 'second' to 'the second, renamed'"
        assert gui.move(gui.chosen(), -1) and load_bookmarks(path) == [renamed, a]
        assert gui.dropdown.value.startswith("1. the second, renamed") and "number 1 of 2" in gui.note.content

        gui._action("delete")
        gui.delete(gui.to_delete)  # "yes, delete"
        assert load_bookmarks(path) == [a] and not gui.confirm_button.visible and gui.note.content == "deleted 'the second, renamed'"
    finally:
        app.stop()


def test_an_edit_of_a_bookmark_gone_from_the_file_is_refused_and_the_list_shows_the_file(tmp_path):
    path, a, b = _two_bookmarks(tmp_path)
    app = _viewer(tmp_path)
    try:
        gui = app.bookmark_gui
        save_bookmarks([a], path)  # "second" deleted by hand (or by another viewer) meanwhile
        assert not gui.rename(b, "new title")
        assert "not renamed:** " in gui.note.content and "no bookmark 'second' in the file any more" in gui.note.content
        assert gui.bookmarks == [a] and load_bookmarks(path) == [a]  # listed as the file is: no stale entry left
    finally:
        app.stop()
