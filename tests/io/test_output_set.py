"""output_set: a command's several outputs appear together at the end, or not at all, and leave no temporary file."""

import os
import signal

import pytest

from evpose.io import atomic
from evpose.io.atomic import atomic_path, output_set


def _write(path, text):
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def test_outputs_of_a_set_appear_only_when_the_set_ends(tmp_path):
    with output_set():
        _write(tmp_path / "a.txt", "A")
        assert not (tmp_path / "a.txt").exists()  # finished, but held back
        with atomic_path(tmp_path / "d", is_dir=True) as tmp:
            (tmp / "x").write_text("X")
        _write(tmp_path / "b.txt", "B")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt", "d"]
    assert (tmp_path / "d" / "x").read_text() == "X"


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, RuntimeError])
def test_an_interrupted_set_leaves_the_earlier_outputs_as_they_were_and_no_temporary_file(tmp_path, interrupt):
    _write(tmp_path / "a.txt", "old A")
    _write(tmp_path / "b.txt", "old B")
    with pytest.raises(interrupt):
        with output_set(remove=(tmp_path / "b.txt",)):
            _write(tmp_path / "a.txt", "new A")
            raise interrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
    assert (tmp_path / "a.txt").read_text() == "old A"


def test_a_ctrl_c_while_the_set_is_renamed_is_raised_once_every_output_is_in_place(tmp_path, monkeypatch):
    publish = atomic._publish
    calls = []

    def publish_then_signal(tmp, dst, is_dir):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)  # lands after the first rename
        calls.append(dst.name)
        publish(tmp, dst, is_dir)

    monkeypatch.setattr(atomic, "_publish", publish_then_signal)
    with pytest.raises(KeyboardInterrupt):
        with output_set():
            for name in ("a.txt", "b.txt", "c.txt"):
                _write(tmp_path / name, name)
    assert calls == ["a.txt", "b.txt", "c.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt", "c.txt"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_files_the_set_replaces_by_nothing_are_removed_with_it(tmp_path):
    _write(tmp_path / "est.map1.txt", "an earlier run's second map")
    with output_set(remove=(tmp_path / "est.map1.txt", tmp_path / "never_there.txt")):
        _write(tmp_path / "est.map0.txt", "map 0")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["est.map0.txt"]


def test_a_set_opened_inside_another_joins_it(tmp_path):
    with output_set():
        with output_set():
            _write(tmp_path / "inner.txt", "i")
        assert not (tmp_path / "inner.txt").exists()
        _write(tmp_path / "outer.txt", "o")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["inner.txt", "outer.txt"]
