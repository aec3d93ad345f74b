"""numpy's own LAPACK gufuncs behind ``np.linalg.eigh`` / ``inv`` / ``solve``, called without the public wrappers.

The wrappers' checks, type resolution and error-state context cost more than the LAPACK call on the 4x4 to 12x12
matrices the tracker handles every update (``eigh`` 12.4 -> 7.1 us, ``inv`` 5.6 -> 3.7 us warm, more in a run where
their Python code is cold). Same call, same bits; a failure (non-finite output) is handed to the public function,
which then raises or returns exactly what it did before.
"""

from __future__ import annotations

import numpy as np

try:  # numpy's own LAPACK gufuncs behind np.linalg.eigh / inv / solve: the same call, the same bits
    from numpy.linalg import _umath_linalg as _lapack
except ImportError:  # another numpy layout: the public functions
    _lapack = None


def eigh(a: np.ndarray):
    """``np.linalg.eigh(a)`` (lower triangle) without its wrapper's checks and error-state context (every update runs
    it); a failure (non-finite output) is handed to ``np.linalg.eigh``, which raises as before."""
    if _lapack is not None:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            w, v = _lapack.eigh_lo(a, signature="d->dd")
        if np.isfinite(w).all():
            return w, v
    return np.linalg.eigh(a)


def inv(a: np.ndarray) -> np.ndarray:
    """``np.linalg.inv(a)`` of a float64 matrix without its wrapper; a singular one goes to ``np.linalg.inv`` (raises)."""
    if _lapack is not None:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            out = _lapack.inv(a, signature="d->d")
        if np.isfinite(out).all():
            return out
    return np.linalg.inv(a)


def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.solve(a, b)`` for a float64 matrix ``b`` without its wrapper; a singular system goes to
    ``np.linalg.solve`` (raises ``LinAlgError``)."""
    if _lapack is not None:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            out = _lapack.solve(a, b, signature="dd->d")
        if np.isfinite(out).all():
            return out
    return np.linalg.solve(a, b)
