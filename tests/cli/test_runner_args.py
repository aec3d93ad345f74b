"""``evpose bench`` / ``evpose sweep``: bad runner arguments, output folders and recording paths fail in one line, before any job."""

from __future__ import annotations

import pytest

from evpose.cli.main import run


@pytest.fixture
def a_file(tmp_path):
    f = tmp_path / "report.txt"
    f.write_text("keep")
    return f


@pytest.mark.parametrize("command", [
    ["bench", "--suite", "quick", "--workers", "0", "--no-progress"],
    ["sweep", "noise_filter.window_us=[1000]", "--recordings", "sim:landing", "--workers", "0", "--no-progress"],
])
@pytest.mark.parametrize("extra, message", [
    (["--workers", "-2"], "--workers must be >= 0"),
    (["--scheduler", "nonsense"], "--scheduler must be an address like tcp://host:8786, got 'nonsense'"),
    (["--out", "{file}"], "report.txt: output folder exists and is a file"),
])
def test_bad_runner_arguments_are_one_line_errors_before_any_job(tmp_path, a_file, capsys, command, extra, message):
    # A malformed scheduler hung 20 s and printed distributed's traceback; an --out file ended in NotADirectoryError.
    extra = [a.replace("{file}", str(a_file)) for a in extra]
    out = [] if "--out" in extra else ["--out", str(tmp_path / "out")]
    assert run([*command, *out, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert a_file.read_text() == "keep" and not (tmp_path / "out").exists()


def test_sweep_recording_that_does_not_exist_is_named_before_the_grid_runs(tmp_path, capsys):
    missing = tmp_path / "nope.h5"
    assert run(["sweep", "noise_filter.window_us=[1000]", "--recordings", f"{missing}::map.ply", "--out", str(tmp_path / "o"),
                "--workers", "0", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{missing}: --recordings {missing}::map.ply: no such file or folder" in err and len(err.splitlines()) == 1


def test_sweep_integer_field_given_text_says_an_integer_is_expected(tmp_path, capsys):
    assert run(["sweep", "noise_filter.window_us=[abc]", "--recordings", "sim:landing", "--out", str(tmp_path / "o"),
                "--workers", "0", "--no-progress"]) == 2
    assert "noise_filter.window_us: expected an integer, got 'abc'" in capsys.readouterr().err
