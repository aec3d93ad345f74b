"""One BLAS kernel set on every x86-64 machine with AVX2, so figures reproduce across machines.

OpenBLAS picks its kernels by CPU at load time. Its AVX-512 kernels round dot
products, ``eigh`` and ``svd`` differently from its AVX2 ones. The tracker and
the SLAM then amplify those last-bit differences (session 8, same code, same
recordings):
- the map builder's points moved by up to 7.5e-14 m;
- ``stpe`` on seed 0 went from 15.77 to 16.50 mm;
- event-only SLAM over 24 landing seeds went from 2.64 % to 3.01 % mean ATE.

With ``OPENBLAS_CORETYPE=Haswell`` an AVX-512 machine reproduces the AVX2
results bit for bit, the bundled ``maps/landing_map.ply`` included.

This only works before numpy loads OpenBLAS, so ``evpose/__init__.py`` calls
it first. A program that imports numpy before evpose keeps its machine's
kernels, and so does a user who set the variable themselves. Such a program's
child processes (the viewer's warm-up) still pin theirs and then disagree with it in
the last bits: the test suite's conftest imports evpose first for that reason. CPUs without AVX2
(and other architectures) are left alone: forcing the kernel set there would
stop the process with an illegal instruction.
"""

from __future__ import annotations

import os
import platform
import sys

CORETYPE = "Haswell"
"""OpenBLAS's AVX2 kernel set (the oldest that every AVX2 CPU runs)."""


def _cpu_has_avx2() -> bool:
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return " avx2" in line
    except OSError:
        return False
    return False


def pin_blas_kernels() -> bool:
    """Set ``OPENBLAS_CORETYPE`` to :data:`CORETYPE` if it can still take effect and the CPU supports it; True if set."""
    if "OPENBLAS_CORETYPE" in os.environ or "numpy" in sys.modules:
        return False
    if platform.machine().lower() not in ("x86_64", "amd64") or not _cpu_has_avx2():
        return False
    os.environ["OPENBLAS_CORETYPE"] = CORETYPE
    return True
