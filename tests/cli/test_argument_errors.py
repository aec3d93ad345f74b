"""Bad command-line arguments are one line and exit 2, as every input error; help and a command's own stderr stay."""

import sys
import types

import pytest

from evpose.cli import main as cli_main
from evpose.cli.argument_errors import flatten_panel


def _fake_command(monkeypatch, main) -> None:
    module = types.ModuleType("fake_args_command")
    module.main = main
    monkeypatch.setitem(sys.modules, "fake_args_command", module)
    monkeypatch.setitem(cli_main.COMMANDS, "fake", ("fake_args_command", "takes a choice and a number"))


def _choose(mode: str = "a", rate_hz: float = 1.0) -> int:
    """A command with a choice and a number.

    Args:
        mode: One of the modes.
        rate_hz: Updates per second.
    """
    if mode not in ("a", "b"):
        raise AssertionError("tyro let a bad choice through")
    print(f"ran {mode} at {rate_hz}", file=sys.stderr)
    return 0


@pytest.mark.parametrize(
    "argv, names",
    [
        (["--mode", "c"], "'c'"),
        (["--rate-hz", "fast"], "--rate-hz"),
        (["--rate-hz"], "--rate-hz"),
        (["--unknown", "1"], "--unknown"),
    ],
)
def test_a_bad_argument_is_one_line_naming_it_and_exit_2(monkeypatch, capsys, argv, names):
    from typing import Literal

    def main(mode: Literal["a", "b"] = "a", rate_hz: float = 1.0) -> int:
        return _choose(mode, rate_hz)

    _fake_command(monkeypatch, main)
    real = sys.stderr
    assert cli_main.run(["fake", *argv]) == 2
    assert sys.stderr is real
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("evpose fake: error: ") and names in err[0] and err[0].endswith("(see evpose fake --help)")
    assert not any(c in err[0] for c in "╭│╰")


def test_good_arguments_run_the_command_with_its_own_stderr(monkeypatch, capsys):
    from typing import Literal

    def main(mode: Literal["a", "b"] = "a", rate_hz: float = 1.0) -> int:
        return _choose(mode, rate_hz)

    _fake_command(monkeypatch, main)
    real = sys.stderr
    assert cli_main.run(["fake", "--mode", "b", "--rate-hz", "2.5"]) == 0
    assert capsys.readouterr().err.strip() == "ran b at 2.5"
    assert sys.stderr is real


def test_help_still_prints_the_full_helptext_and_exits_0(monkeypatch, capsys):
    _fake_command(monkeypatch, _choose)
    with pytest.raises(SystemExit) as exc:
        cli_main.run(["fake", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "usage: evpose fake" in out and "Updates per second" in out


def test_flatten_panel_keeps_the_problem_and_drops_the_box_and_helptext():
    panel = (
        "╭─ Value error ──────────────────────╮\n"
        "│ Error parsing --rate-hz: could not │\n"
        "│ convert 'abc'.                     │\n"
        "│ ────────────────────────────────── │\n"
        "│ Argument helptext:                 │\n"
        "│     --rate-hz FLOAT                │\n"
        "╰────────────────────────────────────╯\n"
    )
    assert flatten_panel(panel) == "Error parsing --rate-hz: could not convert 'abc'."
    assert flatten_panel("") == "invalid arguments"


def test_flatten_panel_reads_the_ascii_layout_of_a_locale_without_box_characters():
    # Where stderr cannot encode the box, rich draws a title, a rule of "-", the text, a rule and the hint: both rules
    # and "For full helptext" ended up in the one line.
    panel = (
        " Invalid choice                                                 \n"
        " -------------------------------------------------------------- \n"
        "  invalid choice 'huge' for argument '--suite'. Expected one of \n"
        "  ('quick', 'full').                                            \n"
        "  --------------------------------------------------------------\n"
        "  For full helptext, run evpose bench --help                    \n"
    )
    assert flatten_panel(panel) == "invalid choice 'huge' for argument '--suite'. Expected one of ('quick', 'full')."


def test_a_bad_argument_on_an_ascii_stderr_is_one_line_without_rules():
    import os
    import subprocess
    from pathlib import Path

    env = {**os.environ, "PYTHONIOENCODING": "ascii", "PYTHONPATH": str(Path(__file__).parents[2])}
    run = subprocess.run([sys.executable, "-m", "evpose", "info", "--width", "x", "."], capture_output=True, text=True, env=env, timeout=60)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and "---" not in run.stderr and "For full helptext" not in run.stderr
    assert run.stderr.startswith("evpose info: error: Error parsing --width:")
