"""Write a simulation: the recording (evpose HDF5 or an ECD text folder), the raw cloud and the true edges.

``out`` ending in ``.h5`` -> evpose HDF5; anything else -> an Event Camera
Dataset folder. Next to it go ``<stem>_cloud.ply`` (open3d binary PLY, grey
colour = albedo) and ``<stem>_edges.npz`` (``segments`` (M, 2, 3) float64,
world frame, metres; ``albedo_segments`` for painted boundaries).
"""

from __future__ import annotations

from pathlib import Path

from evpose.io.atomic import output_set
from evpose.sim.lidar import write_cloud_ply, write_edges_npz
from evpose.sim.simulator import SimulationResult


def output_paths(out: str | Path) -> dict[str, Path]:
    """Where :func:`write_simulation` puts each file for the output path ``out``."""
    out = Path(out)
    stem = out.stem if out.suffix == ".h5" else out.name
    return {"recording": out, "cloud": out.parent / f"{stem}_cloud.ply", "edges": out.parent / f"{stem}_edges.npz"}


def write_simulation(result: SimulationResult, out: str | Path, cloud: bool = True) -> dict[str, Path]:
    """Write the recording, and (if ``cloud``) the raw cloud and edges, as one set (all appear together at the end, or
    none: an interrupt between two left a new recording beside an earlier seed's cloud); returns the paths written."""
    paths = output_paths(out)
    if not cloud:
        del paths["cloud"], paths["edges"]
    with output_set():
        if paths["recording"].suffix == ".h5":
            from evpose.io.h5 import write_recording_h5

            write_recording_h5(paths["recording"], result.recording)
        else:
            from evpose.io.ecd import write_ecd_folder

            write_ecd_folder(paths["recording"], result.recording)
        if cloud:
            write_cloud_ply(paths["cloud"], result.cloud_points, result.cloud_intensity)
            write_edges_npz(paths["edges"], result.edges, result.albedo_edges)
    result.files = dict(paths)
    return paths
