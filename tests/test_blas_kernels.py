"""evpose pins OpenBLAS's kernel set before numpy loads, so results reproduce across x86-64 machines."""

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from evpose.blas_kernels import CORETYPE, _cpu_has_avx2

REPO = Path(__file__).resolve().parents[1]
needs_avx2 = pytest.mark.skipif(not _cpu_has_avx2(), reason="the kernel set is only pinned on CPUs with AVX2")


def _fresh(code: str, **env) -> str:
    e = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    e.update(env)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, check=True, cwd=REPO).stdout.strip()


@needs_avx2
def test_importing_evpose_first_pins_the_avx2_kernel_set():
    assert _fresh("import evpose, os; print(os.environ.get('OPENBLAS_CORETYPE'))") == CORETYPE


def test_a_users_own_choice_and_an_already_loaded_numpy_are_left_alone():
    assert _fresh("import evpose, os; print(os.environ['OPENBLAS_CORETYPE'])", OPENBLAS_CORETYPE="Zen") == "Zen"
    assert _fresh("import numpy, evpose, os; print(os.environ.get('OPENBLAS_CORETYPE'))") == "None"


@needs_avx2
def test_build_map_in_a_fresh_process_reproduces_the_bundled_map_byte_for_byte(tmp_path):
    # The bundled map was built on an AVX2 machine; unpinned, an AVX-512 machine's eigh/svd move its points by ~1e-14 m.
    out = tmp_path / "map.ply"
    _fresh(f"import sys; from evpose.cli.main import run; sys.exit(run(['build-map', 'maps/landing_cloud.ply', '--out', {str(out)!r}]))")
    digest = lambda p: hashlib.sha256(Path(p).read_bytes()).hexdigest()
    assert digest(out) == digest(REPO / "maps" / "landing_map.ply")
