"""Lesson bookmark files: a round trip, malformed files refused with one line naming the file and the problem (and
never written over), atomic writes, rename and reorder on the file as it is now, and a linked file written through."""

import dataclasses
import json

import pytest

from app.app_config import AppConfig
from app.bookmarks import (BOOKMARKS_NAME, Bookmark, add_bookmark, check_title, load_bookmarks, move_bookmark,
                           remove_bookmark, rename_bookmark, save_bookmarks)
from app.layouts import list_layouts
from evpose.errors import InputError

MARK = Bookmark("the TDF valleys", "data0/squares.h5", "data0/squares_map.ply", "tracking", 1_250_000, 124, "TDF", "teaching")


def test_bookmarks_round_trip_and_a_missing_file_is_an_empty_list(tmp_path):
    path = tmp_path / "sub" / "bookmarks.json"
    assert load_bookmarks(path) == []
    other = dataclasses.replace(MARK, title="events only, no map", map=None, mode="slam", stage="events", t_us=0, step=0)
    assert add_bookmark(MARK, path) == [MARK]
    assert add_bookmark(other, path) == [MARK, other]
    assert load_bookmarks(path) == [MARK, other]
    assert remove_bookmark(MARK, path) == [other] == load_bookmarks(path)
    with pytest.raises(InputError, match="no bookmark 'the TDF valleys'"):
        remove_bookmark(MARK, path)


def test_the_bookmarks_file_lies_beside_the_layouts_but_is_not_listed_as_one(tmp_path):
    cfg = AppConfig(layout_dir=tmp_path)
    save_bookmarks([MARK], cfg.bookmarks_path())
    assert cfg.bookmarks_path() == tmp_path / BOOKMARKS_NAME
    assert list_layouts(tmp_path) == {}
    assert AppConfig(bookmarks_file=tmp_path / "x.json").bookmarks_path() == tmp_path / "x.json"


@pytest.mark.parametrize("text, needle", [
    ("{", "not valid JSON"),
    (b"\xff\xfe{", "not UTF-8"),
    ("[]", 'one key, "bookmarks"'),
    ('{"bookmarks": [], "extra": 1}', 'one key, "bookmarks"'),
    ('{"bookmarks": [3]}', r"bookmarks\[0\]: must be an object"),
    ('{"bookmarks": [{"title": "x"}]}', r"bookmarks\[0\].recording: missing key"),
    ("STAGE", r"bookmarks\[1\].stage: 'TDFF' is none of"),
    ("MODE", r"bookmarks\[1\].mode: 'replay' is none of"),
    ("TIME", r"bookmarks\[1\].t_us: must be a whole number >= 0, got -5"),
    ("UNKNOWN", r"bookmarks\[1\].colour: unknown key"),
])
def test_a_malformed_file_is_one_line_naming_the_file_and_the_problem_and_is_not_overwritten(tmp_path, text, needle):
    path = tmp_path / "bookmarks.json"
    good = dataclasses.asdict(MARK)
    bad = {"STAGE": {**good, "stage": "TDFF"}, "MODE": {**good, "mode": "replay"}, "TIME": {**good, "t_us": -5},
           "UNKNOWN": {**good, "colour": "red"}}
    if text in bad:
        text = json.dumps({"bookmarks": [good, bad[text]]})
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    before = path.read_bytes()
    with pytest.raises(InputError, match=needle) as info:
        load_bookmarks(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)
    with pytest.raises(InputError):
        add_bookmark(MARK, path)
    assert path.read_bytes() == before


def test_writes_are_atomic_a_failed_write_leaves_the_old_file_whole(tmp_path, monkeypatch):
    path = tmp_path / "bookmarks.json"
    save_bookmarks([MARK], path)
    before = path.read_bytes()

    def fail(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("pathlib.Path.write_text", fail)
    with pytest.raises(InputError, match="bookmarks.json: cannot write the output .No space left on device"):
        save_bookmarks([MARK, MARK], path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["bookmarks.json"]  # no temporary file left behind


def test_titles_are_one_trimmed_line_and_not_empty_or_too_long():
    assert check_title("  the   TDF\nvalleys ") == "the TDF valleys"
    for title, needle in (("   ", "type a title"), ("x" * 81, "at most 80")):
        with pytest.raises(InputError, match=needle):
            check_title(title)
    assert MARK.label(2) == "2. the TDF valleys (squares.h5, 1.250 s, TDF)"


def test_rename_and_move_edit_the_file_as_it_is_now_and_refuse_a_bookmark_gone_from_it(tmp_path):
    path = tmp_path / "bookmarks.json"
    a, b, c = (dataclasses.replace(MARK, title=t) for t in "abc")
    save_bookmarks([a, b], path)
    add_bookmark(c, path)  # another viewer (or a hand edit) adds one meanwhile: the edits below keep it
    assert move_bookmark(c, -1, path) == ([a, c, b], 1)
    assert move_bookmark(c, -5, path) == ([c, a, b], 0)  # stops at the top
    assert move_bookmark(b, 1, path) == ([c, a, b], 2)  # and at the bottom
    renamed = dataclasses.replace(a, title="the valleys again")
    assert rename_bookmark(a, "  the valleys\nagain ", path) == ([c, renamed, b], 1)
    assert load_bookmarks(path) == [c, renamed, b]
    for edit, needle in ((lambda: rename_bookmark(a, "x", path), "no bookmark 'a'"),
                         (lambda: move_bookmark(a, 1, path), "no bookmark 'a'"),
                         (lambda: rename_bookmark(b, " ", path), "type a title")):
        with pytest.raises(InputError, match=needle):
            edit()
    assert load_bookmarks(path) == [c, renamed, b]


def test_a_bookmarks_file_that_is_a_link_is_written_where_it_points(tmp_path):
    lesson = tmp_path / "lessons" / "optics.json"
    save_bookmarks([MARK], lesson)
    link = tmp_path / "layouts" / "bookmarks" / "bookmarks.json"
    link.parent.mkdir(parents=True)
    link.symlink_to(lesson)
    other = dataclasses.replace(MARK, title="second")
    add_bookmark(other, link)
    assert link.is_symlink() and load_bookmarks(lesson) == [MARK, other]
