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

from evpose.errors import RAISED_INTERRUPTS, EvposeError, interrupt_cause, one_line, printable
from evpose.io import atomic

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


WATCHED_COMMANDS = frozenset({"convert", "simulate", "build-map", "refine-map", "track", "bench", "sweep", "slam", "app"})
"""Commands whose interrupts :mod:`evpose.cli.interrupt_watchdog` enforces: those that run numba kernels (which hold
the main thread for up to a minute, ignoring Ctrl+C) and so pay nothing extra to load its own."""


def _usage() -> str:
    width = max(len(n) for n in COMMANDS)
    lines = ["usage: evpose COMMAND [ARGS...]", "", "commands:"]
    lines += [f"  {name:<{width}}  {desc}" for name, (_, desc) in COMMANDS.items()]
    lines += ["", "Run 'evpose COMMAND --help' for a command's options."]
    return "\n".join(lines)


class _Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, ``timeout``, a service manager), unwound as Ctrl+C is: Python's default ended the process at
    once, leaving the hidden temporary file of an output being written (``.OUT.XXXX.tmp``) behind."""


_raised = RAISED_INTERRUPTS  # the interrupts the signal handlers raised in the current run (evpose.errors)


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
    if "evpose.cli.interrupt_watchdog" in sys.modules:
        sys.modules["evpose.cli.interrupt_watchdog"].stop()  # unwound in time: the watchdog must not say it too
    if isinstance(exc, _Terminated):
        print(f"evpose {name}: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    print(f"evpose {name}: interrupted", file=sys.stderr)
    return 130


def _tell_watchdog(paths, held) -> None:
    from evpose.cli import interrupt_watchdog

    interrupt_watchdog.set_paths(paths)
    interrupt_watchdog.set_held(held)


def _watch(name: str) -> bool:
    """Arm the watchdog that ends the process if an interrupt is not acted on within a second (a numba kernel)."""
    try:
        from evpose.cli import interrupt_watchdog

        if not interrupt_watchdog.start(name, WATCHDOG_GRACE_S):
            return False
    except KeyboardInterrupt:
        raise
    except Exception:  # noqa: BLE001 - no numba/pthreads here: interrupts are acted on as before, between kernels
        return False
    atomic.LISTENERS.append(_tell_watchdog)
    _tell_watchdog(tuple(atomic._LIVE), False)
    return True


WATCHDOG_GRACE_S = 1.5
"""Seconds an interrupt has to unwind through :func:`run` before the watchdog ends the process itself. Signal to exit
took 0.4-1.5 s without it (session 31, /tmp/s31/fuzz31/sig/before.jsonl: track, slam, build-map, simulate, bench,
app --prepare), part of it the interpreter's teardown after :func:`run` returned; at 1.0 s ``build-map``'s own unwinding
and the watchdog both printed their line once in 2 tries."""


def run(argv: list[str], watchdog: bool = False) -> int:
    """Run one subcommand; returns the process exit code. ``watchdog``: the process is this command's own (the console
    script, ``python -m evpose``), which :mod:`evpose.cli.interrupt_watchdog` may end if an interrupt is not acted on
    in time (never a test or a viewer worker calling this in-process)."""
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
    # The viewer itself stops its server and warm-up process on an interrupt (which may take longer); --prepare does not.
    watched = False
    try:
        # Inside the try: arming the watchdog imports numba (a second or more), and a SIGTERM or Ctrl+C landing there
        # printed a 20-line traceback (session 32, /tmp/s32/sig32/).
        watched = (watchdog and previous and name in WATCHED_COMMANDS and not {"-h", "--help"} & set(argv[1:])
                   and (name != "app" or "--prepare" in argv) and _watch(name))
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
        cause = interrupt_cause(exc, swallowed=True)
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
        if watched:
            from evpose.cli import interrupt_watchdog

            interrupt_watchdog.stop()
            atomic.LISTENERS.remove(_tell_watchdog)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        sys.unraisablehook = previous_hook
        _raised.clear()  # acted on: code run after this command (a test's next one) must not see them
    return int(result) if isinstance(result, int) else 0


_exit_now = False
"""Set when an interrupt landed inside C code (see :func:`run`): the library it interrupted may be half-initialised."""


def main() -> None:
    code = run(sys.argv[1:], watchdog=True)
    if _exit_now:
        # open3d interrupted while importing made the interpreter's own shutdown end in exit status 1 or death by
        # SIGINT (3 of 8 tries), after the one-line message: leave without finalising it, with the status promised.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()
