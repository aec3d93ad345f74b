"""Error messages stay on one line whatever a file name or a library's report holds."""

import pytest

from evpose.errors import InputError, one_line


@pytest.mark.parametrize("path, shown", [
    ("/data/two\nlines.h5", "/data/two\\nlines.h5"),  # printed as two lines
    ("/data/red\x1b[31m.h5", "/data/red\\x1b[31m.h5"),  # drove the terminal
    ("/data/tab\there.h5", "/data/tab\\there.h5"),
    ("/data/été.h5", "/data/été.h5"),
])
def test_a_file_name_with_control_characters_is_escaped(path, shown):
    assert str(InputError(path, "no such file")) == f"{shown}: no such file"


def test_a_multi_line_problem_is_joined_into_one_line():
    # h5py and rosbags quote multi-line reports ("file write failed: time = ...\n, filename = ...").
    assert str(InputError("a.h5", "cannot read (failed: time = now\n, errno = 5)", "event 3")) == "a.h5: event 3: cannot read (failed: time = now , errno = 5)"
    assert one_line("a\r\nb\x07") == "a b\\x07"


def test_the_command_line_prints_such_an_error_on_one_line(tmp_path, capsys):
    from evpose.cli.main import run

    assert run(["info", str(tmp_path / "two\nlines.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "two\\nlines.h5: no such file or folder" in err
