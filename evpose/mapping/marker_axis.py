"""The direction a region's painted marker is drawn square to, from all of its fitted straight edges at once.

On a 10 cm scan one straight brightness edge is placed by the few points nearest to it: a
2 m side of the landing's 'H' rests on some 45 points within 12 cm of it, and its free tilt
comes out up to 1-1.5 degrees off (2-3 cm at its ends). The region's own outline is no better
a reference there (its traced direction was 1.2 degrees off the pad's true one on seed 0).
A marker's sides are square to one another, so every fitted side measures the same
direction modulo quarter turns: their length-weighted mean (of ``exp(4 i theta)``) pins it
several times better than any one side, and each side is then fitted at exactly that
direction, only its offset free (:func:`step_fit.fit_step_lines` with ``axis_angle``).
"""

from __future__ import annotations

import numpy as np

from evpose.mapping.albedo_corners import line_runs

MIN_COHERENCE = 0.9
"""The lines' mean of ``exp(4 i theta)``, weighted, must be at least this long: most of them square to one another."""


def fitted_lines(p: np.ndarray, normals: np.ndarray, on_line: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """(unit normal, length m) of each fitted line of an ordered chain (:func:`albedo_corners.line_runs`)."""
    return [(normals[a].copy(), float(np.linalg.norm(p[b - 1] - p[a]))) for a, b in line_runs(normals, on_line)]


def marker_axis(lines: list[tuple[np.ndarray, float]], min_lines: int = 3) -> float | None:
    """The direction (radians, modulo 90 degrees) the fitted ``lines`` share up to quarter turns, or None.

    Each line counts with its squared length (a line's tilt error falls at least as its length
    grows, as the points nearest its ends bound it). None with fewer than ``min_lines`` lines
    or a weighted coherence under :data:`MIN_COHERENCE` (no square marker).
    """
    if len(lines) < min_lines:
        return None
    theta = np.array([np.arctan2(n[1], n[0]) for n, _ in lines])
    w = np.array([length for _, length in lines]) ** 2
    if not w.sum() > 0:
        return None
    z = (w * np.exp(4j * theta)).sum() / w.sum()
    if abs(z) < MIN_COHERENCE:
        return None
    return float(np.angle(z)) / 4.0
