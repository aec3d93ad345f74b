"""Sim(3) / SE(3) alignment of an estimated trajectory to ground truth at the same times (evo's Umeyama).

Used to *look at* estimates in the ground truth's frame (the viewer's SLAM maps),
the same alignment ``evpose eval --atlas --correct-scale`` scores them with
(:func:`evpose.eval.slam_metrics.map_metrics`): the estimate's poses inside the
ground truth's span, the ground truth interpolated at their times, Umeyama on
the positions, with or without scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.trajectory import Trajectory

MIN_POSES = 3
"""Fewest estimates inside the ground truth's span an alignment is made from (as the atlas metrics)."""


@dataclass(frozen=True)
class Sim3:
    """``x -> s R x + t``: from a map's frame to the ground truth's."""

    R: np.ndarray
    """Rotation (3, 3)."""
    t: np.ndarray
    """Translation (3,), metres."""
    s: float
    """Scale, metres per map unit (1 for SE(3))."""

    def points(self, p: np.ndarray) -> np.ndarray:
        """(N, 3) map points -> (N, 3) in the ground truth's frame."""
        p = np.asarray(p, np.float64).reshape(-1, 3)
        return self.s * p @ self.R.T + self.t

    def poses(self, T: np.ndarray) -> np.ndarray:
        """(..., 4, 4) ``T_world_cam`` in the map -> in the ground truth's frame (rotation turned, position mapped)."""
        T = np.asarray(T, np.float64)
        out = T.copy()
        out[..., :3, :3] = self.R @ T[..., :3, :3]
        out[..., :3, 3] = self.s * T[..., :3, 3] @ self.R.T + self.t
        return out


def align_to_ground_truth(est: Trajectory, gt: Trajectory | None, correct_scale: bool = True) -> Sim3 | None:
    """The Umeyama alignment (evo) of ``est``'s positions to ``gt`` at the same times; None without ground truth,
    with fewer than :data:`MIN_POSES` estimates inside its span, or when the positions are degenerate (a line)."""
    from evo.core.geometry import GeometryException, umeyama_alignment

    if gt is None or len(gt) < 2 or est is None or len(est) < MIN_POSES:
        return None
    inside = (est.t >= gt.t[0]) & (est.t <= gt.t[-1])
    if int(inside.sum()) < MIN_POSES:
        return None
    e = est.position[inside]
    r = gt.interpolate(est.t[inside]).position
    try:
        R, t, s = umeyama_alignment(e.T.copy(), r.T.copy(), with_scale=correct_scale)
    except GeometryException:
        return None
    if not (np.all(np.isfinite(R)) and np.all(np.isfinite(t)) and np.isfinite(s) and s > 0):
        return None
    return Sim3(np.asarray(R, np.float64), np.asarray(t, np.float64).reshape(3), float(s))
