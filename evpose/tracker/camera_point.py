"""A map point in the camera frame, and its image rows, for the compiled per-point loops (registration, culling,
crowding, refinement).

Inlined into each kernel, so it costs nothing over writing the three lines out; kept in one place so that every
kernel projects with the same arithmetic, in the same order (their outputs are compared bit for bit).
"""

from __future__ import annotations

import numba as nb


@nb.njit(cache=True, inline="always")
def camera_point(points, i, R_cw, t_cw):
    """(X, Y, Z) of world point ``points[i]`` in the camera frame: ``R_cw @ p + t_cw``."""
    px = points[i, 0]
    py = points[i, 1]
    pz = points[i, 2]
    X = R_cw[0, 0] * px + R_cw[0, 1] * py + R_cw[0, 2] * pz + t_cw[0]
    Y = R_cw[1, 0] * px + R_cw[1, 1] * py + R_cw[1, 2] * pz + t_cw[1]
    Z = R_cw[2, 0] * px + R_cw[2, 1] * py + R_cw[2, 2] * pz + t_cw[2]
    return X, Y, Z


@nb.njit(cache=True, inline="always")
def fill_image_rows(X, Y, Z, pux, puz, pvy, pvz, Ju, Jv):
    """``Ju`` / ``Jv`` := d(u, v) / d(twist) of a camera point (X, Y, Z) (rotation first; d/domega = p x X, d/dv = -p),
    from ``pux`` = du/dX, ``puz`` = du/dZ, ``pvy`` = dv/dY, ``pvz`` = dv/dZ. ``Ju[4]`` and ``Jv[3]`` are always zero and
    left as they are."""
    Ju[0] = -puz * Y
    Ju[1] = puz * X - pux * Z
    Ju[2] = pux * Y
    Ju[3] = -pux
    Ju[5] = -puz
    Jv[0] = pvy * Z - pvz * Y
    Jv[1] = pvz * X
    Jv[2] = -pvy * X
    Jv[4] = -pvy
    Jv[5] = -pvz
