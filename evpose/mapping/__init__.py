"""Contour maps from raw point clouds (EV-Pose section VI-B).

Public API::

    from evpose.mapping import build_contour_map, MapBuildConfig
    cmap = build_contour_map(points, normals=None, intensity=None, config=MapBuildConfig())

``evpose.mapping.edge_metrics.contour_precision_recall`` scores a map against true edges.
"""

from evpose.mapping.build import MapBuildConfig, MapBuildError, build_contour_map

__all__ = ["MapBuildConfig", "MapBuildError", "build_contour_map"]
