"""Motion fits over a whole reconstruction window, from the tracks carried from its start (``ReconstructionWindow.whole_pts``).

A window's own tracks start at its first new tiny frame, half-way through it (the other half is the previous window's
events, ``EventWindowConfig.overlap``), and run between the mean times of its first and last tiny frames: on the
simulated landing they span about a third of the window's events (median 23 of 68 ms), so every warp extrapolates its
motion threefold. The previous window's features, tracked on through this window, span it from its first tiny frame to
its last.

Session 17 (``/tmp/s17/wholewin9/win.py``: the default landing runs of seeds 0, 4, 7, 17, 315 windows; each window's
events re-warped offline and compared with the exact warp, every event ray-cast at its own true pose and projected at
the true reference pose; median over windows, in how many the whole-window fit is closer):

| warp | RMS px | 24 px block-mean px | common shift px |
|---|---|---|---|
| H2, the window's own tracks | 0.636 | 0.162 | 0.083 |
| H2, carried tracks' ends (``MciConfig.sim2_whole_window``) | 0.581 (216 of 300) | 0.151 (185) | 0.084 (154) |
| H5, the window's own tracks | 0.900 | 0.225 | 0.097 |
| H5, carried tracks' two ends | 0.748 (222 of 284) | 0.180 (196) | 0.094 (163) |
| H5, carried tracks in every frame (:func:`fit_twist_rate`) | 0.758 (209) | 0.181 (193) | 0.093 (159) |
| H5, those and the window's own tracks (``MciConfig.parallax_joint_tracks``) | 0.720 (229) | 0.174 (208) | – |

The carried tracks: median 26 per window (the window's own 36) over 6 tiny frames, 55 ms of the window's 66 ms (its
own tracks 22 ms). Whole runs: ``MciConfig.parallax_whole_window`` and ``sim2_whole_window``. An oracle with the true
depths (``/tmp/s17/wholewin9/orunw.py``: H5 with every event's and track's ray-cast depth, competing on sharpness with
H1-H4; landing seeds 0-11): the carried tracks' fit 2.44 % (8 of 12 within 2 %; seed 10 8.85 %), the window's own
tracks' fit 3.14 % (5; seed 10 9.68 %), exact MCIs 1.68 % (10): the motion fit is still part of the gap.
"""

from __future__ import annotations

import numpy as np

from evpose.slam.parallax_warp import project_moved


def whole_span_s(t_us: np.ndarray) -> float:
    """Time between the first and last tiny frame of carried tracks, seconds (0 without two frames)."""
    return (int(t_us[-1]) - int(t_us[0])) / 1e6 if len(t_us) >= 2 else 0.0


def fit_twist_rate(K: np.ndarray, pts: np.ndarray, t_us: np.ndarray, z: np.ndarray, huber_px: float = 1.0,
                   iterations: int = 5, extra: tuple | None = None) -> tuple[np.ndarray, float] | None:
    """The constant camera twist ``(omega, v)`` (6,) per second that moves the tracks ``pts`` (F, M, 2) px, seen at the
    times ``t_us`` (F,) and at depths ``z`` (M,) in their first frame, through all their frames, and the median distance
    of the last frame's positions from where it puts them (px); None when the fit fails or the frames span no time.
    ``extra`` = ``(pts, t_us, z)`` adds a second set of tracks with its own frames (the window's own tracks).

    :func:`evpose.slam.parallax_warp.fit_twist` over every frame instead of the two ends: Gauss-Newton with Huber
    weights on the exact projection, a forward-difference Jacobian and the same small damping.
    """
    pts = np.asarray(pts, np.float64)
    F, M = pts.shape[:2]
    if F < 2 or M < 6 or int(t_us[-1]) <= int(t_us[0]):
        return None
    sets = []
    for p, t, zz in [(pts, t_us, z)] + ([extra] if extra is not None else []):
        p = np.asarray(p, np.float64)
        dt = (np.asarray(t, np.int64)[1:] - int(t[0])) / 1e6
        if len(p) >= 2 and p.shape[1] and dt[-1] > 0:
            X = (np.c_[p[0], np.ones(p.shape[1])] @ np.linalg.inv(K).T) * np.asarray(zz, np.float64)[:, None]
            sets.append((X, dt, p[1:].reshape(-1)))

    def predict(rates: np.ndarray) -> np.ndarray:  # (R, 6) -> (R, every observation's u, v)
        return np.concatenate([project_moved(K, X, (rates[:, None, :] * dt[None, :, None]).reshape(-1, 6)).reshape(len(rates), -1)
                               for X, dt, _ in sets], axis=1)

    obs = np.concatenate([o for _, _, o in sets])
    span = sets[0][1][-1]
    zs = float(np.median(z))
    rate = np.zeros(6)
    h = 1e-6 * np.r_[1.0, 1.0, 1.0, zs, zs, zs] / span
    for _ in range(iterations):
        P = predict(np.vstack([rate, rate + np.diag(h)]))
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
        if np.abs(step[:3]).max() * span < 1e-7 and np.abs(step[3:]).max() * span < 1e-7 * zs:
            break
    last = project_moved(K, sets[0][0], (rate * span)[None])[0]
    return rate, float(np.median(np.linalg.norm(last - pts[-1], axis=1)))
