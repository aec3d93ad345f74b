"""``evpose`` entry point: Ctrl+C at any moment is one line and exit 130."""

import importlib

import pytest

from evpose.cli import main as cli_main


def test_ctrl_c_while_the_command_imports_is_one_line_not_a_traceback(monkeypatch, capsys):
    def interrupted_import(name, *args):
        raise KeyboardInterrupt  # numba/gtsam/open3d take about a second to import: a Ctrl+C lands there

    monkeypatch.setattr(importlib, "import_module", interrupted_import)
    assert cli_main.run(["convert", "in", "out.h5"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["evpose convert: interrupted"]


def test_sigterm_while_an_output_is_written_removes_its_temporary_file_and_exits_143(monkeypatch, tmp_path, capsys):
    # Python's default SIGTERM (kill, timeout) ended the process at once and left `.OUT.XXXX.tmp` behind.
    import os
    import signal
    import sys
    import time
    import types
    from pathlib import Path

    from evpose.io.atomic import atomic_path

    def main(out: Path) -> int:
        with atomic_path(out) as tmp:
            tmp.write_text("half")
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # the handler raises at the next bytecode: never reached
        return 0

    module = types.ModuleType("fake_command")
    module.main = main
    monkeypatch.setitem(sys.modules, "fake_command", module)
    monkeypatch.setitem(cli_main.COMMANDS, "fake", ("fake_command", "writes an output, then is terminated"))
    before = signal.getsignal(signal.SIGTERM)
    assert cli_main.run(["fake", "--out", str(tmp_path / "est.txt")]) == 143
    assert capsys.readouterr().err.strip().splitlines() == ["evpose fake: terminated"]
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) is before


def test_ctrl_c_inside_a_numba_dispatcher_is_one_line_not_a_system_error(monkeypatch, capsys):
    # CPython reports a KeyboardInterrupt raised while a C function (numba's dispatcher) runs Python code as a
    # SystemError "returned a result with an exception set", caused by it: a traceback and exit 1 in `simulate`.
    def interrupted_import(name, *args):
        raise SystemError("CPUDispatcher(<function _shade>) returned a result with an exception set") from KeyboardInterrupt()

    monkeypatch.setattr(importlib, "import_module", interrupted_import)
    assert cli_main.run(["simulate", "--scenario", "landing", "--out", "x.h5"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["evpose simulate: interrupted"]


def test_ctrl_c_while_open3d_imports_is_one_line_not_an_import_error(monkeypatch, capsys):
    # pybind11 turns a KeyboardInterrupt during open3d's module initialisation into "ImportError: initialization
    # failed" raised from it: `evpose simulate` interrupted 1 s in printed that traceback and exited 1.
    def interrupted_import(name, *args):
        raise ImportError("initialization failed") from KeyboardInterrupt()

    monkeypatch.setattr(importlib, "import_module", interrupted_import)
    assert cli_main.run(["simulate", "--scenario", "landing", "--out", "x.h5"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["evpose simulate: interrupted"]


def test_ctrl_c_swallowed_by_c_code_that_then_fails_is_one_line_and_exit_130(monkeypatch, capsys):
    # A Ctrl+C landing in numba's compiler callback (ctypes) is printed as "Exception ignored on calling ctypes callback
    # function" with its traceback, and numba then fails with "RuntimeError: no compiled object yet": `build-map`
    # interrupted during a first run's compilation printed both and exited 1.
    import os
    import signal
    import sys
    import types

    def main() -> int:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(10**6):  # the handler raises at the next bytecode
                pass
        except KeyboardInterrupt as exc:  # what the C callback does with it
            sys.unraisablehook(types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=exc, exc_traceback=None,
                                                     err_msg="Exception ignored on calling ctypes callback function", object=None))
        raise RuntimeError("no compiled object yet for <Library 'front_layer'>")

    module = types.ModuleType("fake_compiling_command")
    module.main = main
    monkeypatch.setitem(sys.modules, "fake_compiling_command", module)
    monkeypatch.setitem(cli_main.COMMANDS, "fake", ("fake_compiling_command", "compiles, is interrupted, fails"))
    before = signal.getsignal(signal.SIGINT), sys.unraisablehook
    assert cli_main.run(["fake"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["evpose fake: interrupted"]
    assert (signal.getsignal(signal.SIGINT), sys.unraisablehook) == before


def test_an_error_without_an_interrupt_is_still_raised(monkeypatch):
    def broken_import(name, *args):
        raise RuntimeError("a bug")

    monkeypatch.setattr(importlib, "import_module", broken_import)
    import pytest

    with pytest.raises(RuntimeError, match="a bug"):
        cli_main.run(["convert", "in", "out.h5"])


def test_an_unknown_command_is_one_line_with_the_closest_command(capsys):
    # The whole usage (15 lines) followed the error.
    assert cli_main.run(["trak", "x.h5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("evpose: error: unknown command 'trak'; did you mean 'track'? commands: info, convert,")


def test_a_file_the_user_may_not_read_is_one_line_naming_it(monkeypatch, capsys, tmp_path):
    # Readers without their own check ended in a PermissionError traceback; the HDF5 sniffing called it "not an HDF5
    # file (bad signature)". (Root reads anything, hence the simulated refusal.)
    import builtins

    path = tmp_path / "theirs.h5"
    path.write_bytes(b"\x89HDF\r\n\x1a\n")
    real_open = builtins.open

    def refusing_open(file, *args, **kwargs):
        if str(file) == str(path):
            raise PermissionError(13, "Permission denied", str(file))
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", refusing_open)
    assert cli_main.run(["info", str(path)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"evpose info: error: {path}: Permission denied"]


@pytest.mark.parametrize("argv", [["info", "{long}.h5"], ["eval", "{long}.txt", "gt.txt"], ["convert", "in.h5", "{long}.h5"]])
def test_a_file_name_longer_than_the_file_system_takes_is_one_line(tmp_path, monkeypatch, capsys, argv):
    # Path.exists() raises ENAMETOOLONG: an OSError traceback in every command.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "in.h5").write_bytes(b"")
    long = "a" * 300
    assert cli_main.run([a.format(long=long) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith("File name too long") and long in err[0]
