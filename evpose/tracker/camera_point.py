"""A map point in the camera frame, for the compiled per-point loops (registration, culling, crowding, refinement).

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
