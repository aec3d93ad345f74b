"""Motion fits over a whole reconstruction window, from the tracks carried from its start (``ReconstructionWindow.whole_pts``).

A window's own tracks start at its first new tiny frame, half-way through it (the other half is the previous window's
events, ``EventWindowConfig.overlap``), and run between the mean times of its first and last tiny frames: on the
simulated landing they span about a third of the window's events (median 23 of 68 ms), so every warp extrapolates its
motion threefold. The previous window's features, tracked on through this window, span it from its first tiny frame to
its last.
"""

from __future__ import annotations

import numpy as np

from evpose.slam.parallax_warp import _project_moved


def whole_span_s(t_us: np.ndarray) -> float:
    """Time between the first and last tiny frame of carried tracks, seconds (0 without two frames)."""
    return (int(t_us[-1]) - int(t_us[0])) / 1e6 if len(t_us) >= 2 else 0.0


def fit_twist_rate(K: np.ndarray, pts: np.ndarray, t_us: np.ndarray, z: np.ndarray, huber_px: float = 1.0,
                   iterations: int = 5) -> tuple[np.ndarray, float] | None:
    """The constant camera twist ``(omega, v)`` (6,) per second that moves the tracks ``pts`` (F, M, 2) px, seen at the
    times ``t_us`` (F,) and at depths ``z`` (M,) in their first frame, through all their frames, and the median distance
    of the last frame's positions from where it puts them (px); None when the fit fails or the frames span no time.

    :func:`evpose.slam.parallax_warp.fit_twist` over every frame instead of the two ends: Gauss-Newton with Huber
    weights on the exact projection, a forward-difference Jacobian and the same small damping.
    """
    pts = np.asarray(pts, np.float64)
    F, M = pts.shape[:2]
    dt = (np.asarray(t_us, np.int64)[1:] - int(t_us[0])) / 1e6
    if F < 2 or M < 6 or dt[-1] <= 0:
        return None
    X = (np.c_[pts[0], np.ones(M)] @ np.linalg.inv(K).T) * np.asarray(z, np.float64)[:, None]
    zs = float(np.median(z))
    obs = pts[1:].reshape(-1)
    rate = np.zeros(6)
    h = 1e-6 * np.r_[1.0, 1.0, 1.0, zs, zs, zs] / dt[-1]
    for _ in range(iterations):
        rates = np.vstack([rate, rate + np.diag(h)])  # (7, 6)
        P = _project_moved(K, X, (rates[:, None, :] * dt[None, :, None]).reshape(-1, 6)).reshape(7, -1)  # per rate: (F-1)*M*2
        r0 = P[0] - obs
        J = ((P[1:] - P[0]) / h[:, None]).T
        e = np.hypot(r0[0::2], r0[1::2])
        w = np.where(e > huber_px, huber_px / np.maximum(e, 1e-12), 1.0).repeat(2)
        A = J.T @ (J * w[:, None])
        A += 1e-6 * np.trace(A) / 6.0 * np.eye(6)
        step = np.linalg.solve(A, -(J.T @ (w * r0)))
        rate = rate + step
        if not np.all(np.isfinite(rate)):
            return None
        if np.abs(step[:3]).max() * dt[-1] < 1e-7 and np.abs(step[3:]).max() * dt[-1] < 1e-7 * zs:
            break
    last = _project_moved(K, X, (rate * dt[-1])[None])[0]
    return rate, float(np.median(np.linalg.norm(last - pts[-1], axis=1)))
