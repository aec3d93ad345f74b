"""The single ``evpose`` entry point.

Subcommands are resolved lazily: only the module of the command being run is
imported, so ``evpose info`` does not pay for importing gtsam, open3d or viser.
Each module exposes ``main(...)``; its signature and docstring are the CLI (tyro).
Errors caused by input (:class:`~evpose.errors.EvposeError`) print one line and exit 2.
"""

from __future__ import annotations

import importlib
import signal
import sys
import threading

from evpose.errors import EvposeError

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


def _terminate(signum, frame) -> None:
    raise _Terminated


def _interrupted(name: str, exc: KeyboardInterrupt) -> int:
    """One line and the shell's exit code for a Ctrl+C (130) or a SIGTERM (143)."""
    if isinstance(exc, _Terminated):
        print(f"evpose {name}: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    print(f"evpose {name}: interrupted", file=sys.stderr)
    return 130


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
        print(f"evpose: error: unknown command {name!r}\n\n{_usage()}", file=sys.stderr)
        return 2
    # Only the main thread may set a handler (tests and the viewer's workers call run() from others).
    previous = signal.signal(signal.SIGTERM, _terminate) if threading.current_thread() is threading.main_thread() else None
    try:
        # Importing a command takes about a second (numba, gtsam, open3d): a Ctrl+C then printed a 40-line traceback.
        from evpose.cli.argument_errors import run_tyro

        module = importlib.import_module(COMMANDS[name][0])
        result = run_tyro(module.main, argv[1:], f"evpose {name}")
    except EvposeError as exc:
        print(f"evpose {name}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # Output piped into e.g. `head`, which closed early: not an error of ours.
        sys.stderr.close()
        return 0
    except KeyboardInterrupt as exc:
        return _interrupted(name, exc)
    except SystemError as exc:
        # A Ctrl+C or SIGTERM landing while a numba dispatcher runs Python code (typing, its cache) surfaces as
        # "CPUDispatcher(...) returned a result with an exception set", caused by the KeyboardInterrupt (CPython chains
        # it as __cause__): seen once in `simulate` (`_shade`), as a traceback and exit 1.
        if isinstance(exc.__cause__, KeyboardInterrupt):
            return _interrupted(name, exc.__cause__)
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return int(result) if isinstance(result, int) else 0


def main() -> None:
    sys.exit(run(sys.argv[1:]))


if __name__ == "__main__":
    main()
