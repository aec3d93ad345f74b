"""Corners of a brightness-edge chain: its fitted straight lines continued to where they meet.

Canny on a sparse scan smoothed at twice the point spacing rounds every corner of a painted
marker: on the landing's 'H' (10 cm scan, 20 cm smoothing) a chain leaves a straight side
10-25 cm before the corner and cuts across it on a curve up to 6 cm inside or outside the
true outline, and :func:`step_fit.fit_step_lines` leaves those curved pieces as they are
(too short and too bent for a line). Where two consecutive fitted lines of one chain meet at
a clear angle, the corner is where the lines cross: each line is continued to that point and
the curved points between them are dropped. A line is placed by all the raw points along
its run, so its continuation carries its sub-spacing accuracy into the corner; the curve
was placed by the smoothed image, whose corner is rounded by construction.
"""

from __future__ import annotations

import math

import numpy as np


def line_runs(normals: np.ndarray, fitted: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [a, b) of consecutive fitted points sharing one normal (one fitted line each)."""
    runs = []
    m = fitted.size
    i = 0
    while i < m:
        if not fitted[i]:
            i += 1
            continue
        j = i + 1
        while j < m and fitted[j] and np.array_equal(normals[j], normals[i]):
            j += 1
        runs.append((i, j))
        i = j
    return runs


def complete_corners(p: np.ndarray, normals: np.ndarray, fitted: np.ndarray, spacing: float,
                     min_angle_deg: float, max_reach: float, min_run: int) -> tuple[np.ndarray, np.ndarray]:
    """Continue consecutive fitted lines of an ordered chain to their crossing where they meet at a corner.

    ``p`` (M, 2) chain points in plane coordinates, ``normals`` (M, 2) their unit normals (dark ->
    bright), ``fitted`` (M,) the points :func:`step_fit.fit_step_lines` put on a line (a line's
    points share its normal exactly). Two lines of at least ``min_run`` points each, consecutive
    along the chain (only unfitted points between them), whose normals differ by at least
    ``min_angle_deg``, and whose crossing lies within ``max_reach`` m of both facing line ends and
    ahead of them (not inside either line), are each continued to the crossing at ``spacing``;
    the points between them are dropped. Everything else stays as it is. Returns the new
    points and normals in chain order.
    """
    runs = [r for r in line_runs(normals, fitted) if r[1] - r[0] >= min_run]
    if len(runs) < 2:
        return p, normals
    cos_min = math.cos(math.radians(min_angle_deg))
    pieces_p, pieces_n = [], []
    cursor = 0
    for (a1, b1), (a2, b2) in zip(runs[:-1], runs[1:]):
        n1, n2 = normals[a1], normals[a2]
        if abs(float(n1 @ n2)) > cos_min:
            continue
        # Lines n . x = c through their own points (each line's points lie exactly on it).
        c1, c2 = float(p[a1] @ n1), float(p[a2] @ n2)
        det = n1[0] * n2[1] - n1[1] * n2[0]
        if abs(det) < 1e-9:
            continue
        x = np.array([(c1 * n2[1] - c2 * n1[1]) / det, (n1[0] * c2 - n2[0] * c1) / det])
        end1, start2 = p[b1 - 1], p[a2]
        d1 = np.array([n1[1], -n1[0]])
        d1 *= np.sign((end1 - p[a1]) @ d1) or 1.0  # along line 1 towards its end
        d2 = np.array([n2[1], -n2[0]])
        d2 *= np.sign((p[b2 - 1] - start2) @ d2) or 1.0  # along line 2 away from its start
        reach1 = float((x - end1) @ d1)   # how far line 1 goes on to the crossing
        reach2 = float((start2 - x) @ d2)  # how far line 2 starts after it
        # A line may also run a little past the crossing (its run took in the start of the curve):
        # its points beyond the crossing are dropped, up to half the reach.
        if not (-0.5 * max_reach <= reach1 <= max_reach and -0.5 * max_reach <= reach2 <= max_reach):
            continue
        s1 = max(a1, cursor)  # the previous corner may have cut this line's start
        keep1 = np.flatnonzero((p[s1:b1] - x) @ d1 < -0.25 * spacing) + s1
        skip2 = int(np.count_nonzero((p[a2:b2] - x) @ d2 <= 0.25 * spacing))
        if keep1.size == 0 or skip2 >= b2 - a2:
            continue
        pieces_p.append(p[cursor:s1])
        pieces_n.append(normals[cursor:s1])
        pieces_p.append(p[keep1])
        pieces_n.append(normals[keep1])
        end1 = p[keep1[-1]]
        reach1 = float((x - end1) @ d1)
        start2 = p[a2 + skip2]
        reach2 = float((start2 - x) @ d2)
        k1 = int(math.floor(max(reach1, 0.0) / spacing))
        if k1 > 0:
            pieces_p.append(end1 + (np.arange(1, k1 + 1) * spacing)[:, None] * d1)
            pieces_n.append(np.repeat(n1[None], k1, axis=0))
        k2 = int(math.floor(max(reach2, 0.0) / spacing))
        # The crossing itself once, on line 2's side; then line 2's continuation back up to its start.
        if k2 >= 0 and reach2 > 0.25 * spacing:
            pts2 = x + (np.arange(0, k2 + 1) * spacing)[:, None] * d2
            pts2 = pts2[(pts2 - x) @ d2 < reach2 - 0.25 * spacing]
            pieces_p.append(pts2)
            pieces_n.append(np.repeat(n2[None], pts2.shape[0], axis=0))
        cursor = a2 + skip2
    if cursor == 0 and not pieces_p:
        return p, normals
    pieces_p.append(p[cursor:])
    pieces_n.append(normals[cursor:])
    return np.concatenate(pieces_p), np.concatenate(pieces_n)
