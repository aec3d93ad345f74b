"""A bad value for an optional flag (``int | None``) is named plainly: its kind and the value, no Python classes."""

from __future__ import annotations

import pytest

from evpose.cli.main import run


@pytest.mark.parametrize("flag, value, kind", [("--smoothed-lag", "abc", "an integer"), ("--smoothed-lag", "1.5", "an integer"),
                                               ("--width", "x", "an integer"), ("--rate-hz", "fast", "a number")])
def test_a_bad_value_of_an_optional_flag_says_what_was_expected(tmp_path, capsys, flag, value, kind):
    code = run(["track", str(tmp_path / "r.h5"), "--map", str(tmp_path / "m.ply"), "--out", str(tmp_path / "e.txt"), flag, value])
    assert code == 2
    assert capsys.readouterr().err == (f"evpose track: error: Error parsing {flag}: expected {kind}, got '{value}'"
                                       " (see evpose track --help)\n")


def test_other_argument_errors_pass_unchanged(capsys):
    assert run(["bench", "--suite", "huge"]) == 2
    assert capsys.readouterr().err == ("evpose bench: error: invalid choice 'huge' for argument '--suite'. Expected one of"
                                       " ('quick', 'full'). (see evpose bench --help)\n")
