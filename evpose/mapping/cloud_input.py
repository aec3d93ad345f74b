"""Reading a raw scan for map building: positions plus whatever normals, colour or intensity it carries."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evpose.errors import InputError
from evpose.io.map_ply import read_point_cloud


@dataclass
class RawCloud:
    """A raw scan as map building consumes it."""

    points: np.ndarray
    """Positions, float64 (N, 3), metres."""
    normals: np.ndarray | None
    """Per-point normals from the file, float64 (N, 3), or None."""
    intensity: np.ndarray | None
    """Brightness per point (luma of the colours, or the file's ``intensity`` field), float64 (N,), or None."""


@contextlib.contextmanager
def _quiet_open3d():
    """open3d prints its own warnings for unreadable files; our one-line error says it better."""
    import open3d as o3d

    level = o3d.utility.get_verbosity_level()
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    try:
        yield o3d
    finally:
        o3d.utility.set_verbosity_level(level)


def load_cloud(path: str | Path) -> RawCloud:
    """Read a ``.ply``/``.pcd`` (or other open3d) cloud; raises :class:`InputError` for anything unusable."""
    from evpose.mapping.brightness import intensity_from_colors

    path = Path(path)
    with _quiet_open3d() as o3d:
        try:
            points, extra = read_point_cloud(path)
        except InputError as exc:
            if exc.problem == "point cloud is empty":
                raise InputError(path, "no points could be read (an empty cloud, or not a point-cloud file)") from None
            raise
        except (RuntimeError, ValueError, OSError) as exc:
            raise InputError(path, f"cannot read the point cloud ({exc})") from None
        # The tensor reader handles double-precision PCD fields (the legacy one reads them
        # as zeros) and scalar 'intensity' fields; prefer it whenever it finds the points.
        tcloud = o3d.t.io.read_point_cloud(str(path))
        if "positions" in tcloud.point and tcloud.point["positions"].shape[0] == points.shape[0]:
            points = tcloud.point["positions"].numpy().astype(np.float64)
            bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
            if bad.size:
                raise InputError(path, "NaN or infinite coordinate", f"point {int(bad[0])}")
            if "normals" in tcloud.point:
                extra["normals"] = tcloud.point["normals"].numpy().astype(np.float64)
            if "colors" in tcloud.point:
                raw_colors = tcloud.point["colors"].numpy()
                colors = raw_colors.astype(np.float64)
                if np.issubdtype(raw_colors.dtype, np.integer):  # uchar channels are 0..255
                    colors /= float(np.iinfo(raw_colors.dtype).max)
                extra["colors"] = colors
        intensity = None
        if "colors" in extra:
            intensity = intensity_from_colors(extra["colors"])
        elif "intensity" in tcloud.point:
            values = tcloud.point["intensity"].numpy().astype(np.float64).reshape(-1)
            if values.shape[0] == points.shape[0]:
                intensity = values
    if intensity is not None:
        bad = np.flatnonzero(~np.isfinite(intensity))
        if bad.size:
            raise InputError(path, "NaN or infinite intensity", f"point {int(bad[0])}")
    normals = extra.get("normals")
    if normals is not None and not np.isfinite(normals).all():
        normals = None
    return RawCloud(points, normals, intensity)
