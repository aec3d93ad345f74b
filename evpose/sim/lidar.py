"""A LiDAR-like raw point cloud of a scene's static geometry, and its PLY/NPZ files.

Points are drawn uniformly over the visible static surfaces at a configurable
density (a survey scan merged from many stations looks like that), displaced
along the surface normal by Gaussian range noise. Ground hidden inside a box
(under a building) is removed, as a scanner never sees it. Each point's
intensity is the surface albedo (with texture), which map building uses to
derive brightness signs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evpose.io.atomic import atomic_path
from evpose.sim.render import albedo_at_points
from evpose.sim.scenes import Scene


@dataclass(frozen=True)
class LidarConfig:
    """Density and noise of the raw cloud."""

    density_per_m2: float = field(default=100.0, metadata={"min": 1.0, "max": 5000.0, "unit": "points/m^2"})
    """Mean number of points per square metre of surface."""
    range_noise_m: float = field(default=0.005, metadata={"min": 0.0, "max": 0.1, "unit": "m"})
    """Standard deviation of the range noise (applied along the surface normal), metres."""
    max_range_m: float = 15.0
    """Only surfaces within this horizontal distance of the scene centre are scanned, metres."""


def _inside_boxes(points: np.ndarray, scene: Scene) -> np.ndarray:
    """Points strictly inside any closed static box (ground under buildings), by ray parity against the static mesh."""
    import open3d as o3d

    rc = o3d.t.geometry.RaycastingScene()
    rc.add_triangles(o3d.core.Tensor(scene.static.vertices.astype(np.float32)), o3d.core.Tensor(scene.static.triangles.astype(np.uint32)))
    # Boxes have no bottom face, so a point under a roof crosses it once going up (odd parity);
    # a closed room adds one crossing through its ceiling for every point.
    origin = points + np.array([0.0, 0.0, 0.002])
    rays = np.concatenate([origin, np.tile([0.0, 0.0, 1.0], (points.shape[0], 1))], axis=1).astype(np.float32)
    counts = rc.count_intersections(o3d.core.Tensor(rays)).numpy().astype(np.int64)
    if scene.closed:
        counts = np.maximum(counts - 1, 0)  # points on the ceiling itself see nothing above
    return counts % 2 == 1


def sample_cloud(scene: Scene, cfg: LidarConfig, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 3) float64 and intensity (N,) float64 in 0..1."""
    mesh = scene.static
    v = mesh.vertices[mesh.triangles]
    areas = mesh.face_areas()
    pts_all, face_all = [], []
    for f in range(mesh.n_faces):
        a, b, c = v[f]
        n = int(rng.poisson(areas[f] * cfg.density_per_m2))
        if n == 0:
            continue
        r1 = np.sqrt(rng.random(n))
        r2 = rng.random(n)
        p = (1 - r1)[:, None] * a + (r1 * (1 - r2))[:, None] * b + (r1 * r2)[:, None] * c
        pts_all.append(p)
        face_all.append(np.full(n, f, np.int64))
    pts = np.concatenate(pts_all)
    faces = np.concatenate(face_all)
    keep = (np.abs(pts[:, 0]) <= cfg.max_range_m) & (np.abs(pts[:, 1]) <= cfg.max_range_m)
    pts, faces = pts[keep], faces[keep]
    hidden = _inside_boxes(pts, scene) & (np.abs(mesh.face_normals()[faces, 2]) > 0.99)
    pts, faces = pts[~hidden], faces[~hidden]
    intensity = albedo_at_points(pts, faces, mesh.albedo, mesh.texture, mesh.texture_scale, mesh.texture_amp, mesh.texture_center)
    if cfg.range_noise_m > 0:
        pts = pts + mesh.face_normals()[faces] * (cfg.range_noise_m * rng.standard_normal(len(pts)))[:, None]
    return pts, np.clip(intensity, 0.0, 1.0)


def write_cloud_ply(path: str | Path, points: np.ndarray, intensity: np.ndarray) -> None:
    """Binary PLY: positions (float64) and grey colours = intensity in [0, 1] as 8-bit (open3d's own layout).

    Written with numpy rather than open3d: on a full disk open3d's PLY writer printed a line per point to stderr and
    kept the deleted temporary file open. The bytes are what ``open3d.io.write_point_cloud`` wrote (its header, and
    colours clipped to [0, 1] and rounded), so recordings simulated before and after are the same files."""
    points = np.asarray(points, np.float64)
    n = len(points)
    rec = np.empty(n, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    rec["x"], rec["y"], rec["z"] = points.T
    grey = np.round(np.clip(np.asarray(intensity, np.float64), 0.0, 1.0) * 255.0).astype(np.uint8)
    rec["red"] = rec["green"] = rec["blue"] = grey
    header = ["ply", "format binary_little_endian 1.0", "comment Created by Open3D", f"element vertex {n}"]
    header += [f"property double {c}" for c in "xyz"] + [f"property uchar {c}" for c in ("red", "green", "blue")]
    header.append("end_header")
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(("\n".join(header) + "\n").encode("ascii"))
            fh.write(rec.tobytes())


def write_edges_npz(path: str | Path, segments: np.ndarray, albedo_segments: np.ndarray | None = None) -> None:
    """``segments`` (M, 2, 3) float64 world-frame metres (and ``albedo_segments`` for painted boundaries)."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            extra = {} if albedo_segments is None else {"albedo_segments": np.asarray(albedo_segments, np.float64)}
            np.savez_compressed(fh, segments=np.asarray(segments, np.float64), **extra)
