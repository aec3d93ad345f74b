"""Geometric rims placed where the events put them, but only while other edges anchor the pose (session 40, off).

The built map places the rims of raised regions (the landing pad's 15 cm sides, crate tops) point by point; the
pad's are 4.7-5.8 mm RMS off the truth against ~1.2 mm for the other geometric edges (``/tmp/s39/tr39``, seeds 0 /
17 / 43), and late in the 240x180 landing they are half the visible edges. :mod:`evpose.tracker.edge_offsets` learns
only the part of their offsets no pose change explains, and the painted-edge refiner
(:mod:`evpose.tracker.map_refinement`) learns the whole offset, pose error included (refining every geometric rim
that way cost +1.17 mm, session 39). Here a rim point takes the refiner's absolute step (to where its field is zero,
clipped, a small gain), but only in an update where the registered points that no refiner moves (feet, vertical
edges, rims without a brightness sign) are at least ``anchor_share`` of the registered points: their pose is then
what the rims are learned against. The absolute offset moves the edge-offset learner's base, so the two add up.

Measured (session 40, ``full``, 2 s landing from ground truth, built maps, CLI path paired per seed against main's
defaults 4.934 mm, ``/tmp/s40/tr40`` ``run.sh``, ``cmp.py``, ``cfg/ar50*.yaml``): 240x180 seeds 0-23 with
``anchor_share`` 0.5 (rims refined until ~1.0 s, while 48-63 % of the registered points anchor; 23-33 % after 1.25 s)
5.095 mm (+0.161 +- 0.037, 6 of 24 better), with ``gain`` 0.01 seeds 0-9 +0.107 +- 0.084 (4 of 10): worse, so off.
Why (``/tmp/s40/tr40/blame.py``: the field registration's Gauss-Newton step from the TRUE pose in 1.3-2 s, split by
point class, seeds 0 / 3 / 17 / 24 / 27 / 43): the pad's rims pull a few millimetres (camera y +3.6 to +5.7 mm after
1.6 s on every seed, a common bias), the painted 'H' (its refined points) up to 24 mm along the shift / tilt ridge on
the worst seeds: the late pull is the H's, not the rims'.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.core.lapack_calls import inv
from evpose.tracker.map_refinement import _NO_GAUGE, _refine_kernel
from evpose.tracker.registration_kernels import _NO_EXTRA, _NO_TANGENTS, _NO_TWIST


@dataclass
class AnchoredRimConfig:
    """Absolute refinement of the geometric rims with a brightness sign while others anchor (``full`` at 240x180 with
    :mod:`evpose.tracker.edge_offsets`; off)."""

    anchor_share: float = field(default=0.0, metadata={"min": 0.0, "max": 1.0, "step": 0.05, "unit": "ratio"})
    """Refine the rims only in updates where the registered points no refiner moves are at least this share of the
    registered points (0 = off), ratio."""
    gain: float = field(default=0.03, metadata={"min": 0.0, "max": 1.0, "step": 0.01, "unit": "ratio"})
    """Share of each update's measured step a rim point moves by, ratio."""
    step_clip_px: float = field(default=0.25, metadata={"min": 0.01, "max": 5.0, "step": 0.05, "unit": "px"})
    """Largest step one update measures for one point, pixels (before ``gain``)."""
    max_offset_m: float = field(default=0.02, metadata={"min": 0.0, "max": 0.5, "step": 0.005, "unit": "m"})
    """Largest absolute offset of a rim point from the map's position, metres."""


def rim_points(contour_map: ContourMap, max_curvature: float) -> np.ndarray:
    """(N,) bool: geometric points (surface variation at least ``max_curvature``) with a brightness sign and a known
    edge normal, the rims the painted-edge refiner leaves alone."""
    known_normal = np.any(contour_map.edge_normal != 0, axis=1)
    return (contour_map.brightness_sign != 0) & (contour_map.curvature >= max_curvature) & known_normal


class AnchoredRims:
    """Absolute offsets of the rim points along their edge normals, written through an edge-offset learner's base."""

    def __init__(self, config: AnchoredRimConfig, contour_map: ContourMap, max_curvature: float, learner,
                 painted: np.ndarray | None):
        """``learner`` the :class:`~evpose.tracker.edge_offsets.EdgeOffsetLearner` whose points these are (only the rim
        points it owns are refined), ``painted`` (N,) bool the painted-edge refiner's points (None: none)."""
        self.config = config
        self.learner = learner
        mask = rim_points(contour_map, max_curvature) & learner._owned
        self.index = np.flatnonzero(mask).astype(np.int64)
        self._mapped = np.ascontiguousarray(learner._base[self.index])  # the map's positions, before any offset
        self._normals = np.ascontiguousarray(learner._normals[self.index])
        self._moving = mask if painted is None else mask | np.asarray(painted, dtype=np.bool_)
        """(N,) bool: points some refiner moves; the others anchor."""
        self.offsets = np.zeros(self.index.size)
        """Absolute offset of each rim point along its unit edge normal, metres."""
        self.seen = np.zeros(self.index.size, dtype=np.int64)
        self.last_share = float("nan")
        """The last update's share of anchoring points among the registered ones."""

    def update(self, points: np.ndarray, used: np.ndarray, field_, T_world_cam_field: np.ndarray, K: np.ndarray) -> int:
        """One update (after the edge-offset learner's): the rims' steps if the anchoring share holds; returns the
        points moved."""
        c = self.config
        self.last_share = float(np.count_nonzero(~self._moving[used])) / max(int(used.size), 1)
        if self.index.size == 0 or c.anchor_share <= 0 or c.gain <= 0 or self.last_share < c.anchor_share:
            return 0
        base = self._mapped + self.learner.offsets[self.index, None] * self._normals  # where the learner has them
        T_cw = inv(np.asarray(T_world_cam_field, dtype=np.float64))
        mr_thr, mr_grad = 0.7, 0.05  # the painted refiner's inlier and slope tests (its defaults)
        moved = int(_refine_kernel(points, self.index, base, self._normals, self.offsets, self.seen,
                                   np.ascontiguousarray(T_cw[:3, :3]), np.ascontiguousarray(T_cw[:3, 3]), float(K[0, 0]),
                                   float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), field_.value, field_.grad_u, field_.grad_v,
                                   field_.box, float(c.gain), float(c.max_offset_m), float(c.step_clip_px), mr_thr, mr_grad, 0,
                                   _NO_GAUGE, False, _NO_TANGENTS, _NO_TWIST, 0.0, 0.0, _NO_EXTRA))
        self._write_base()
        return moved

    def _write_base(self) -> None:
        self.learner._base[self.index] = self._mapped + self.offsets[:, None] * self._normals

    def snapshot(self) -> tuple[np.ndarray, np.ndarray]:
        return np.copy(self.offsets), np.copy(self.seen)

    def restore(self, state: tuple[np.ndarray, np.ndarray]) -> None:
        self.offsets, self.seen = np.copy(state[0]), np.copy(state[1])
        self._write_base()

    def apply(self, points: np.ndarray) -> None:
        """Nothing of its own: the learner's ``apply`` (restored after this) writes base plus its offsets."""
