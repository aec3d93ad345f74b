import subprocess
import sys


def test_python_m_evpose_runs_the_evpose_command():
    out = subprocess.run([sys.executable, "-m", "evpose", "--help"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    for command in ("track", "slam", "app"):
        assert command in out.stdout
