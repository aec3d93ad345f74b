"""Map-construction benchmarks: build time on large synthetic scans, and accuracy/time per simulated scene.

* ``build_synthetic``: a grid of boxes on a ground plane, 2500 points/m^2 with 5 mm range
  noise; ~1 M points (full) or ~0.25 M (quick). Reports wall time, points/s and the
  precision/recall against the known edges.
* ``scene_<name>``: the simulator's raw LiDAR-like cloud of each bundled scene (default
  density and noise), scored against the scene's true edges - the geometric ones
  (``Scene.edges``) and the painted ones (``Scene.albedo_edges``, the landing pad's 'H'),
  since the map now traces brightness edges too - as the issue defines it: precision =
  contour points within 2 cm of a true edge; recall = visible edge length (raw points
  within 5 cm) with a contour point within 2 cm. ``albedo_recall`` is the recall of the
  painted edges alone (when the scene has any). ``recall_faces`` is the recall under the
  faithful definition of "visible in the scan" (:mod:`evpose.mapping.edge_metrics`: both
  faces meeting at the edge sampled within one point spacing, ``1/sqrt(density)``, of it),
  reported beside the old one.

Timings on a shared machine are noisy: ``build_s`` is wall time, ``cpu_s`` the process CPU
time (what the build costs when it has a core to itself), ``load_1min`` the load average
at the end; each figure is one build (a build is seconds to tens of seconds, so repeats
would cost more than they tell).
"""

from __future__ import annotations

import os
import time

import numpy as np

from evpose.bench import BenchContext
from evpose.bench.stats import peak_rss_mb


def _box_grid(half_extent: float, seed: int):
    from evpose.mapping.synthetic import Box

    rng = np.random.default_rng(seed)
    boxes = []
    step = 2.5
    for x in np.arange(-half_extent + 1.5, half_extent - 1.0, step):
        for y in np.arange(-half_extent + 1.5, half_extent - 1.0, step):
            sx, sy = rng.uniform(0.5, 1.4, 2)
            boxes.append(Box((float(x), float(y)), (float(sx), float(sy), float(rng.uniform(0.2, 1.5))),
                             yaw_deg=float(rng.uniform(-40, 40)), albedo_top=float(rng.uniform(0.1, 0.9))))
    return tuple(boxes)


def _score(cmap, points, segments, density: float) -> dict:
    from evpose.mapping.edge_metrics import contour_precision_recall, edge_faces

    m = contour_precision_recall(cmap.points, segments, tolerance_m=0.02, cloud=points, visible_radius_m=0.05)
    f = contour_precision_recall(cmap.points, segments, tolerance_m=0.02, cloud=points,
                                 visible_radius_m=1.0 / np.sqrt(density), faces=edge_faces(segments))
    return {
        "precision": round(m["precision"], 4),
        "recall": round(m["recall"], 4),
        "recall_faces": round(f["recall"], 4),
        "contour_points": m["n_points"],
        "visible_edge_m": round(m["visible_length_m"], 2),
        "visible_edge_faces_m": round(f["visible_length_m"], 2),
        "p95_distance_m": round(m["p95_distance_m"], 4),
    }


def build_synthetic(ctx: BenchContext) -> dict:
    from evpose.mapping import build_contour_map
    from evpose.mapping.synthetic import boxes_on_ground

    half = 5.0 if ctx.quick else 10.0
    scan = boxes_on_ground(_box_grid(half, ctx.seed), half_extent=half, density=2500.0, noise_m=0.005, seed=ctx.seed)
    build_contour_map(scan.points[:20000])  # numba compilation / cache load outside the timing
    t0, c0 = time.perf_counter(), time.process_time()
    cmap = build_contour_map(scan.points, intensity=scan.intensity)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    out = {"cloud_points": int(scan.points.shape[0]), "build_s": round(wall, 2), "cpu_s": round(cpu, 2),
           "mpoints_per_s": round(scan.points.shape[0] / wall / 1e6, 3), "load_1min": round(os.getloadavg()[0], 2)}
    out.update(_score(cmap, scan.points, scan.edges, 2500.0))
    out["peak_rss_mb"] = round(peak_rss_mb(), 1)
    return out


def _scene(name: str):
    def bench(ctx: BenchContext) -> dict:
        from evpose.mapping import build_contour_map
        from evpose.sim.lidar import LidarConfig, sample_cloud
        from evpose.sim.scene_library import SceneName, build_scene

        scene = build_scene(SceneName(name))
        lidar = LidarConfig()
        points, intensity = sample_cloud(scene, lidar, np.random.default_rng(ctx.seed))
        build_contour_map(points[:20000])
        t0, c0 = time.perf_counter(), time.process_time()
        cmap = build_contour_map(points, intensity=intensity)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        out = {"cloud_points": int(points.shape[0]), "build_s": round(wall, 2), "cpu_s": round(cpu, 2),
               "load_1min": round(os.getloadavg()[0], 2)}
        edges = np.concatenate([scene.edges, scene.albedo_edges]) if scene.albedo_edges.size else scene.edges
        out.update(_score(cmap, points, edges, lidar.density_per_m2))
        if scene.albedo_edges.size:
            from evpose.mapping.edge_metrics import contour_precision_recall

            out["albedo_recall"] = round(contour_precision_recall(cmap.points, scene.albedo_edges, cloud=points)["recall"], 4)
        out["brightness_known_share"] = round(float(np.mean(cmap.brightness_sign != 0)), 3)
        return out

    return bench


BENCHMARKS = {
    "build_synthetic": build_synthetic,
    "scene_landing": _scene("landing"),
    "scene_indoor": _scene("indoor"),
}
