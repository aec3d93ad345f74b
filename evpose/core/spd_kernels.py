"""Inverse of a small symmetric positive-definite matrix by its Cholesky factor, for compiled per-update code (the 6x6
normal equations and covariances of the registrations) that would otherwise leave numba for two LAPACK calls
(``eigvalsh`` to test definiteness, then ``inv``). The test is the factorisation itself: a pivot that is not > 0
(or NaN) means not positive definite, as an eigenvalue test's ``not min > 0`` does except for matrices within
rounding of singular. Equal to LAPACK's inverse to rounding, not bit for bit.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def spd_inverse(A, out):
    """``out`` := inverse of the symmetric part ``(A + A^T) / 2`` of the (n, n) ``A``, exactly symmetric; returns
    False (``out`` undefined) when that part is not positive definite or not finite."""
    n = A.shape[0]
    L = np.zeros((n, n))
    for j in range(n):
        d = A[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return False
        L[j, j] = np.sqrt(d)
        for i in range(j + 1, n):
            s = 0.5 * (A[i, j] + A[j, i])
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / L[j, j]
    # L^-1 (lower) by forward substitution, then A^-1 = L^-T L^-1.
    M = np.zeros((n, n))
    for j in range(n):
        M[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, n):
            s = 0.0
            for k in range(j, i):
                s -= L[i, k] * M[k, j]
            M[i, j] = s / L[i, i]
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(j, n):
                s += M[k, i] * M[k, j]
            out[i, j] = s
            out[j, i] = s
    for i in range(n):
        for j in range(n):
            if not np.isfinite(out[i, j]):
                return False
    return True
