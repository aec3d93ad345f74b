"""``evpose build-map CLOUD --out MAP.ply``: contour map from a raw point cloud (EV-Pose VI-B)."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import tyro

from evpose.errors import InputError


def main(
    cloud: tyro.conf.Positional[Path],
    out: Path,
    voxel: float = 0.0,
    k: int = 16,
    angle_deg: float = 15.0,
    plane_angle_deg: float = 25.0,
    curvature: float = 0.06,
    min_region: int = 25,
    plane_distance: float = 0.015,
    cell: float = 0.0,
    spacing: float = 0.01,
    adjacent: float = 0.0,
    no_snap: bool = False,
    no_robust_normals: bool = False,
    no_albedo_edges: bool = False,
    merge_double: float = 0.0,
    viewpoint: tuple[float, float, float] | None = None,
    config: Path | None = None,
    quiet: bool = False,
) -> int:
    """Build a contour map (PLY with edge normals, plane normals, regions, curvature, brightness signs) from a raw .ply/.pcd cloud.

    Args:
        cloud: Raw scan (.ply or .pcd; normals, colours or intensity are used when present).
        out: Output contour map (.ply); never the input file.
        voxel: Voxel size for downsampling before processing, metres (0 = none).
        k: Neighbours for PCA normals/curvature and region growing.
        angle_deg: Largest normal angle between neighbours in one region, degrees.
        plane_angle_deg: Largest angle between a point's normal and its region's mean normal, degrees.
        curvature: Curvature limit lambda0/(lambda0+lambda1+lambda2) for growing a region.
        min_region: Smallest region kept, points.
        plane_distance: Distance within which edge points join a neighbouring region's plane, metres.
        cell: Raster cell for contour tracing, metres (0 = 1.5x median point spacing).
        spacing: Distance between contour points, metres.
        adjacent: A boundary needs another surface within this distance, else it is the scan's rim, metres (0 = auto).
        no_snap: Do not snap contour points onto the intersection line of adjacent planes.
        no_robust_normals: Grow regions on plain kNN PCA normals (no one-sided refit at creases and parallel layers).
        no_albedo_edges: Do not trace brightness (painted/albedo) edges inside regions from the cloud's colour or intensity.
        merge_double: Merge contour points of different regions closer than this into one (an edge traced from both sides), metres (0 = keep both).
        viewpoint: Where the scan was seen from (x y z, metres); plane normals face it.
        config: Every builder setting (``evpose.mapping.build.MapBuildConfig``) as YAML/JSON; the flags above
            override it where they differ from their defaults.
        quiet: No progress bar or summary.
    """
    from evpose.io.atomic import check_outputs
    from evpose.io.map_ply import write_contour_map
    from evpose.mapping.build import MapBuildConfig, MapBuildError, build_contour_map
    from evpose.mapping.cloud_input import load_cloud

    if out.exists() and cloud.exists() and os.path.samefile(out, cloud):
        raise InputError(out, "refusing to overwrite the input cloud")
    if out.suffix.lower() != ".ply":
        raise InputError(out, "the contour map is written as PLY; use a .ply output name")
    check_outputs((out,), inputs=(cloud, config))
    t0 = time.perf_counter()
    flags = dict(
        voxel_m=voxel, k_neighbours=k, angle_threshold_deg=angle_deg, plane_angle_deg=plane_angle_deg,
        curvature_limit=curvature, min_region_points=min_region, plane_distance_m=plane_distance,
        cell_m=cell, contour_spacing_m=spacing, adjacent_m=adjacent, snap=not no_snap, viewpoint=viewpoint,
        albedo_edges=not no_albedo_edges, merge_double_m=merge_double, robust_normals=not no_robust_normals,
    )
    if config is None:
        cfg = MapBuildConfig(**flags)
    else:
        from evpose.io.config_file import read_config

        import dataclasses

        defaults = MapBuildConfig()
        cfg = dataclasses.replace(read_config(MapBuildConfig, config),
                                  **{name: v for name, v in flags.items() if v != getattr(defaults, name)})
    from evpose.io.config_file import check_config

    check_config(cfg)
    raw = load_cloud(cloud)
    try:
        cmap = build_contour_map(raw.points, raw.normals, raw.intensity, cfg, progress=not quiet and sys.stderr.isatty())
    except MapBuildError as exc:
        raise InputError(cloud, exc.problem, exc.record) from None
    write_contour_map(out, cmap, comment=f"evpose contour map from {cloud.name}")
    if not quiet:
        n_regions = len(set(cmap.region_id.tolist()))
        known = float((cmap.brightness_sign != 0).mean()) if len(cmap) else 0.0
        print(f"{out}: {len(cmap)} contour points on {n_regions} regions from {raw.points.shape[0]} cloud points, "
              f"brightness sign known for {100 * known:.1f} %, {time.perf_counter() - t0:.1f} s")
    return 0
