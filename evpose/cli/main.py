"""The single ``evpose`` entry point.

Subcommands are resolved lazily: only the module of the command being run is
imported, so ``evpose info`` does not pay for importing gtsam, open3d or viser.
Each module exposes ``main(...)``; its signature and docstring are the CLI (tyro).
Errors caused by input (:class:`~evpose.errors.EvposeError`) print one line and exit 2.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading

from evpose.errors import EvposeError, one_line, printable

# name -> (module, one-line description). Order is the order of ``evpose --help``.
COMMANDS: dict[str, tuple[str, str]] = {
    "info": ("evpose.cli.info", "describe a recording, map or trajectory"),
    "convert": ("evpose.cli.convert", "convert a recording to evpose HDF5"),
    "simulate": ("evpose.cli.simulate", "simulate an event camera + IMU recording with ground truth"),
    "build-map": ("evpose.cli.build_map", "build a contour map from a raw point cloud"),
    "refine-map": ("evpose.cli.refine_map", "move a map's edges to where a tracked recording's events see them"),
    "track": ("evpose.cli.track", "track the camera pose against a map (EV-Pose)"),
    "eval": ("evpose.cli.eval", "compare an estimated trajectory with ground truth"),
    "bench": ("evpose.cli.bench", "run the benchmark suite and write a report"),
    "sweep": ("evpose.cli.sweep", "evaluate a parameter grid over recordings"),
    "slam": ("evpose.cli.slam", "map-free event(-inertial) SLAM"),
    "app": ("evpose.cli.app", "start the browser-based viewer"),
}


def _usage() -> str:
    width = max(len(n) for n in COMMANDS)
    lines = ["usage: evpose COMMAND [ARGS...]", "", "commands:"]
    lines += [f"  {name:<{width}}  {desc}" for name, (_, desc) in COMMANDS.items()]
    lines += ["", "Run 'evpose COMMAND --help' for a command's options."]
    return "\n".join(lines)


class _Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, ``timeout``, a service manager), unwound as Ctrl+C is: Python's default ended the process at
    once, leaving the hidden temporary file of an output being written (``.OUT.XXXX.tmp``) behind."""


_raised: list[KeyboardInterrupt] = []
"""The interrupts the signal handlers raised in the current :func:`run`: C code may swallow one and fail otherwise."""


def _terminate(signum, frame) -> None:
    exc = _Terminated()
    _raised.append(exc)
    raise exc


def _interrupt(signum, frame) -> None:
    """Python's own SIGINT handler, remembering what it raised."""
    exc = KeyboardInterrupt()
    _raised.append(exc)
    raise exc


def _quiet_unraisable(previous):
    """``sys.unraisablehook`` leaving out a KeyboardInterrupt that C code could not raise (numba's compiler callback
    prints "Exception ignored on calling ctypes callback function" and its 10-line traceback); :func:`run` reports it."""
    def hook(unraisable):
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            return
        previous(unraisable)

    return hook


def _interrupted(name: str, exc: KeyboardInterrupt) -> int:
    """One line and the shell's exit code for a Ctrl+C (130) or a SIGTERM (143)."""
    if isinstance(exc, _Terminated):
        print(f"evpose {name}: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    print(f"evpose {name}: interrupted", file=sys.stderr)
    return 130


def _interrupt_cause(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl+C, or SIGTERM as :class:`_Terminated`) that ``exc`` was raised from, if any."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, KeyboardInterrupt):
            return exc
        exc = exc.__cause__ or exc.__context__
    return None


def run(argv: list[str]) -> int:
    """Run one subcommand; returns the process exit code."""
    if not argv or argv[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0 if argv else 2
    if argv[0] == "--version":
        from evpose import __version__

        print(__version__)
        return 0
    name = argv[0]
    if name not in COMMANDS:
        # One line like every other error (the whole usage followed it: 15 lines); close matches first.
        import difflib

        close = difflib.get_close_matches(name, COMMANDS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        print(f"evpose: error: unknown command {name!r}; {hint}commands: {', '.join(COMMANDS)} (see evpose --help)", file=sys.stderr)
        return 2
    # Only the main thread may set a handler (tests and the viewer's workers call run() from others). An ignored
    # SIGINT (nohup, a background job) stays ignored.
    previous = {}
    if threading.current_thread() is threading.main_thread():
        previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, _terminate)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            previous[signal.SIGINT] = signal.signal(signal.SIGINT, _interrupt)
    previous_hook = sys.unraisablehook
    if previous:
        sys.unraisablehook = _quiet_unraisable(previous_hook)
    _raised.clear()
    try:
        # Importing a command takes about a second (numba, gtsam, open3d): a Ctrl+C then printed a 40-line traceback.
        from evpose.cli.argument_errors import run_tyro

        module = importlib.import_module(COMMANDS[name][0])
        result = run_tyro(module.main, argv[1:], f"evpose {name}")
    except EvposeError as exc:
        print(f"evpose {name}: error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # Output piped into e.g. `head`, which closed early: not an error of ours.
        sys.stderr.close()
        return 0
    except KeyboardInterrupt as exc:
        return _interrupted(name, exc)
    except Exception as exc:
        # A Ctrl+C or SIGTERM landing inside C code that runs Python surfaces as another exception, caused by the
        # KeyboardInterrupt: a numba dispatcher's SystemError "CPUDispatcher(...) returned a result with an exception
        # set" (seen in `simulate`'s `_shade`), pybind11's "ImportError: initialization failed" when it lands while
        # open3d imports (`simulate` 1 s in, 2 of 7 tries); or after it, when the C code swallowed it: numba's
        # "RuntimeError: no compiled object yet" when it lands in a compilation (`build-map` 6 s in, a first run).
        # A traceback and exit 1 each.
        cause = _interrupt_cause(exc) or (_raised[-1] if _raised else None)
        if cause is not None:
            global _exit_now
            _exit_now = True  # the C code may be left half-initialised: see main()
            return _interrupted(name, cause)
        if isinstance(exc, OSError) and exc.filename is not None:
            # The system refusing a path a reader or writer without its own check was given: a file another user owns
            # (PermissionError), a name longer than the file system takes (every command: a traceback), a symlink loop.
            print(f"evpose {name}: error: {printable(str(exc.filename))}: {exc.strerror or exc}", file=sys.stderr)
            return 2
        raise
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        sys.unraisablehook = previous_hook
    return int(result) if isinstance(result, int) else 0


_exit_now = False
"""Set when an interrupt landed inside C code (see :func:`run`): the library it interrupted may be half-initialised."""


def main() -> None:
    code = run(sys.argv[1:])
    if _exit_now:
        # open3d interrupted while importing made the interpreter's own shutdown end in exit status 1 or death by
        # SIGINT (3 of 8 tries), after the one-line message: leave without finalising it, with the status promised.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()
