"""Load the trajectories ``evpose eval`` compares: TUM files, or the ground truth of any recording."""

from __future__ import annotations

import math
from pathlib import Path

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError

TUM_SUFFIXES = (".txt", ".tum", ".csv")


def is_tum_file(path: Path) -> bool:
    """A text file (by suffix, or whose first data line has 8 numbers) is read as TUM; anything else as a recording."""
    from evpose.io.tum import is_tum_file as sniff

    return path.is_file() and (path.suffix.lower() in TUM_SUFFIXES or sniff(path))


def load_estimate(path: str | Path) -> Trajectory:
    """An estimated trajectory from a TUM file."""
    from evpose.io.tum import read_tum

    path = Path(path)
    if not path.exists():
        raise InputError(path, "is a folder, not a file" if path.is_dir() else "no such file")
    traj = read_tum(path)
    traj.validate(str(path))
    return traj


def load_ground_truth(path: str | Path) -> Trajectory:
    """Ground truth from a TUM file or from any recording ``open_recording`` reads (ECD folder, evpose HDF5, ...)."""
    path = Path(path)
    if not path.exists():
        raise InputError(path, "no such file or folder")
    if is_tum_file(path):
        return load_estimate(path)
    from evpose.io.open import open_recording

    recording = open_recording(path)
    gt = recording.ground_truth
    if gt is None or len(gt) == 0:
        raise InputError(path, "recording has no ground truth")
    gt.validate(str(path))
    return gt


def atlas_paths(estimate: Path) -> list[Path]:
    """The per-map files ``evpose slam --out EST.txt`` writes next to EST (``EST.map0.txt``, ``EST.map1.txt``...), in map order.

    Without any, the atlas is EST alone (a single-map run, or a trajectory from another system).
    """
    import re

    estimate = Path(estimate)
    suffix = estimate.suffix or ".txt"
    pattern = re.compile(re.escape(estimate.stem) + r"\.map(\d+)" + re.escape(suffix) + "$")
    found = []
    if estimate.parent.is_dir():
        for p in estimate.parent.iterdir():
            m = pattern.match(p.name)
            if m and p.is_file():
                found.append((int(m.group(1)), p))
    return [p for _, p in sorted(found)] or [estimate]


def atlas_duration_s(estimate: Path) -> float | None:
    """The recording span stated in ``EST.slam.json`` (``evpose slam``'s summary), if that file is there and says it."""
    import json

    summary = Path(estimate).with_suffix(".slam.json")
    if not summary.is_file():
        return None
    try:
        value = json.loads(summary.read_text()).get("duration_s")
    except (ValueError, AttributeError):
        raise InputError(summary, "not a JSON object (expected evpose slam's summary)") from None
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) and value > 0 else None
