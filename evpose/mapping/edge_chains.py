"""Linking the pixels of a thin edge map (Canny output) into ordered chains."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _walk(edges, visited, y, x, buf_r, buf_c):
    """Follow unvisited set pixels from (y, x), marking them; returns how many were appended to the buffers."""
    h, w = edges.shape
    # 4-neighbours before diagonals: the walk follows the curve rather than cutting corners.
    dy = (0, 1, 0, -1, 1, 1, -1, -1)
    dx = (1, 0, -1, 0, 1, -1, 1, -1)
    n = 0
    while True:
        found = False
        for d in range(8):
            yy = y + dy[d]
            xx = x + dx[d]
            if 0 <= yy < h and 0 <= xx < w and edges[yy, xx] and not visited[yy, xx]:
                visited[yy, xx] = True
                y = yy
                x = xx
                found = True
                break
        if not found:
            return n
        buf_r[n] = y
        buf_c[n] = x
        n += 1


@numba.njit(cache=True)
def _trace_chains(edges):
    """Link the set pixels of a thin edge map into 8-connected chains, in raster order.

    Returns (rows, cols, starts): chain c is pixels ``starts[c]:starts[c+1]``. Curves are
    traced from their endpoints first so open curves come out whole; what is left (loops,
    branch remainders) is traced both ways from its first pixel in raster order.
    """
    h, w = edges.shape
    n_set = 0
    for y in range(h):
        for x in range(w):
            if edges[y, x]:
                n_set += 1
    visited = np.zeros((h, w), np.bool_)
    rows = np.empty(n_set, np.int32)
    cols = np.empty(n_set, np.int32)
    starts = np.empty(n_set + 1, np.int64)
    fr = np.empty(n_set, np.int32)
    fc = np.empty(n_set, np.int32)
    br = np.empty(n_set, np.int32)
    bc = np.empty(n_set, np.int32)
    n_chains = 0
    n_out = 0
    for phase in range(2):
        for y0 in range(h):
            for x0 in range(w):
                if not edges[y0, x0] or visited[y0, x0]:
                    continue
                if phase == 0:
                    deg = 0
                    for yy in range(max(y0 - 1, 0), min(y0 + 2, h)):
                        for xx in range(max(x0 - 1, 0), min(x0 + 2, w)):
                            if (yy != y0 or xx != x0) and edges[yy, xx]:
                                deg += 1
                    if deg != 1:
                        continue
                visited[y0, x0] = True
                n_f = _walk(edges, visited, y0, x0, fr, fc)
                n_b = _walk(edges, visited, y0, x0, br, bc) if phase == 1 else 0
                starts[n_chains] = n_out
                n_chains += 1
                for i in range(n_b - 1, -1, -1):
                    rows[n_out] = br[i]
                    cols[n_out] = bc[i]
                    n_out += 1
                rows[n_out] = y0
                cols[n_out] = x0
                n_out += 1
                for i in range(n_f):
                    rows[n_out] = fr[i]
                    cols[n_out] = fc[i]
                    n_out += 1
    starts[n_chains] = n_out
    return rows, cols, starts[:n_chains + 1]
