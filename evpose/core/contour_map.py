"""Contour maps: the 3D points EV-Pose registers events against, with per-point edge geometry."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ContourMap:
    """Object-contour points in the world frame with the attributes tracking needs.

    ``brightness_sign`` fixes the direction of the brightness gradient once for the
    whole project: the gradient (dark -> bright) points along
    ``brightness_sign * edge_normal``. 0 means unknown (learned online).
    """

    points: np.ndarray
    """Positions in the world, float64 (N, 3), metres."""
    edge_normal: np.ndarray
    """Unit in-plane outward normal of the contour (points away from the region), float32 (N, 3); zero if unknown."""
    plane_normal: np.ndarray
    """Unit normal of the surface the contour bounds, float32 (N, 3); zero if unknown."""
    region_id: np.ndarray
    """Surface region the point belongs to, int32 (N,); -1 if none."""
    curvature: np.ndarray
    """Surface variation lambda0/(lambda0+lambda1+lambda2) at the point, float32 (N,)."""
    brightness_sign: np.ndarray
    """+1 if brightness rises along ``edge_normal``, -1 if it falls, 0 unknown; int8 (N,)."""

    @classmethod
    def from_points(cls, points: np.ndarray, **attributes) -> "ContourMap":
        """A map from bare positions; missing attributes are filled with 'unknown'."""
        pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        n = pts.shape[0]
        defaults = {
            "edge_normal": np.zeros((n, 3), np.float32),
            "plane_normal": np.zeros((n, 3), np.float32),
            "region_id": np.full(n, -1, np.int32),
            "curvature": np.zeros(n, np.float32),
            "brightness_sign": np.zeros(n, np.int8),
        }
        for key, value in attributes.items():
            if key not in defaults:
                raise TypeError(f"unknown contour-map attribute {key!r}")
            defaults[key] = np.ascontiguousarray(value, dtype=defaults[key].dtype).reshape(defaults[key].shape)
        return cls(pts, **defaults)

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def __getitem__(self, index) -> "ContourMap":
        return ContourMap(
            self.points[index],
            self.edge_normal[index],
            self.plane_normal[index],
            self.region_id[index],
            self.curvature[index],
            self.brightness_sign[index],
        )

    @property
    def has_edge_normals(self) -> bool:
        return bool(len(self)) and bool(np.any(self.edge_normal != 0))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.points.min(axis=0), self.points.max(axis=0)
