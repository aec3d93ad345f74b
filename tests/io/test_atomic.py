"""atomic_path: all-or-nothing outputs that never replace an input."""

import pytest

from evpose.errors import InputError
from evpose.io.atomic import atomic_path


def test_output_appears_only_on_success(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "out.txt") as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with atomic_path(tmp_path / "out.txt") as tmp:
        tmp.write_text("done")
    assert (tmp_path / "out.txt").read_text() == "done"


def test_refuses_to_replace_an_input(tmp_path):
    f = tmp_path / "in.txt"
    f.write_text("keep")
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        with atomic_path(f, inputs=(f,)):
            pass
    assert f.read_text() == "keep"


def test_folders_are_replaced_whole(tmp_path):
    with atomic_path(tmp_path / "d", is_dir=True) as tmp:
        (tmp / "a").write_text("1")
    with atomic_path(tmp_path / "d", is_dir=True) as tmp:
        (tmp / "b").write_text("2")
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == ["b"]
