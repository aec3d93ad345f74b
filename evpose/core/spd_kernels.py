"""Inverse of a small symmetric positive-definite matrix by its Cholesky factor, and the eigenvalues of a small
symmetric one by Jacobi rotations, for compiled per-update code (the 6x6
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


@nb.njit(cache=True)
def sym_eigenvalues(A, w):
    """``w`` := the eigenvalues of the symmetric part of the (n, n) finite ``A``, ascending (cyclic Jacobi rotations
    until the off-diagonal part is below rounding: as LAPACK's to ~1e-15 relative for the registrations' 6x6, and a
    small eigenvalue of a well-scaled matrix to about its own precision)."""
    n = A.shape[0]
    a = np.empty((n, n))
    frob = 0.0
    for i in range(n):
        for j in range(n):
            a[i, j] = 0.5 * (A[i, j] + A[j, i])
            frob += a[i, j] * a[i, j]
    for _ in range(60):
        off = 0.0
        for p in range(n - 1):
            for q in range(p + 1, n):
                off += a[p, q] * a[p, q]
        if not off > 1e-36 * frob:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if a[p, q] == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * a[p, q])
                if abs(theta) > 1e150:
                    t = 0.5 / theta
                else:
                    t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):
                    akp, akq = a[k, p], a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(n):
                    apk, aqk = a[p, k], a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
    for i in range(n):
        w[i] = a[i, i]
    w.sort()
