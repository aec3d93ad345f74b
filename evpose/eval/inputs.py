"""Load the trajectories ``evpose eval`` compares: TUM files, or the ground truth of any recording."""

from __future__ import annotations

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
        raise InputError(path, "no such file")
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
