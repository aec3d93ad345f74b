"""A Ctrl+C or SIGTERM that lands inside a long numba kernel (which holds the main thread and never checks for signals)
ends the command within seconds: one line, exit 130 / 143, no traceback, no temporary output file left
(evpose/cli/interrupt_watchdog.py). Before it, the command went on until the kernel returned (up to a minute in
``build-map``)."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SPIN = textwrap.dedent('''
    import sys, numba
    from pathlib import Path
    from evpose.cli import main as m
    from evpose.io.atomic import atomic_path

    @numba.njit
    def spin(n):  # one kernel call of about a minute
        s = 0.0
        for i in range(n):
            s += (i % 7) * 1e-9
        return s

    def command(out: Path) -> int:
        spin(10)
        with atomic_path(out) as tmp:
            tmp.write_text("partial")
            Path(str(out) + ".started").touch()
            spin(60_000_000_000)
        return 0

    sys.modules["spin_command"] = type(sys)("spin_command")
    sys.modules["spin_command"].main = command
    m.COMMANDS["track"] = ("spin_command", "a numba kernel of a minute")
    sys.argv = ["evpose", "track", "--out", sys.argv[1]]
    m.main()
''')


@pytest.mark.parametrize("sig,code,word", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_an_interrupt_inside_a_numba_kernel_ends_the_command_at_once_without_its_temporary_output(tmp_path, sig, code, word):
    out = tmp_path / "out" / "est.txt"
    out.parent.mkdir()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # As from a terminal: a harness run in the background (or under time(1)) ignores SIGINT, which Python then keeps.
    proc = subprocess.Popen([sys.executable, "-c", SPIN, str(out)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        started = Path(str(out) + ".started")
        end = time.monotonic() + 60
        while not started.exists() and proc.poll() is None and time.monotonic() < end:
            time.sleep(0.05)
        assert started.exists(), proc.communicate(timeout=5)
        time.sleep(0.3)  # inside the kernel
        proc.send_signal(sig)
        sent = time.monotonic()
        _, err = proc.communicate(timeout=30)  # the kernel alone would take about a minute
        waited = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
    lines = err.decode().strip().splitlines()
    assert proc.returncode == code and lines == [f"evpose track: {word}"], (proc.returncode, lines)
    assert waited < 15
    assert sorted(p.name for p in out.parent.iterdir()) == ["est.txt.started"]  # no .est.txt.XXXX.tmp
