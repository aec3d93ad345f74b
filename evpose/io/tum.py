"""TUM trajectory files: one pose per line, ``t tx ty tz qx qy qz qw``, t in seconds, pose = ``T_world_cam``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evpose.core.trajectory import Trajectory, quaternion_problem
from evpose.errors import InputError
from evpose.io.atomic import atomic_path
from evpose.io.text_table import TimeUnit, read_table, write_table


def read_tum(path: str | Path, unit: TimeUnit = TimeUnit.SECONDS) -> Trajectory:
    """Read a TUM file (``#`` comments allowed). Times must strictly increase; quaternions are normalised."""
    lines: list[int] = []
    t, v = read_table(path, 8, unit=unit, line_numbers=lines)
    if t.size == 0:
        raise InputError(path, "contains no poses")
    bad = quaternion_problem(v[:, 3:7])
    if bad is not None:
        raise InputError(path, bad[1], f"line {lines[bad[0]]}")
    traj = Trajectory.from_arrays(t, v[:, 0:3], v[:, 3:7])
    try:
        traj.validate(str(path))  # e.g. a position beyond the Earth (`evpose info` described a 1e12 m trajectory)
    except InputError as exc:
        pose = exc.record.split()[-1] if exc.record and exc.record.startswith("pose ") else None
        raise InputError(path, exc.problem, f"line {lines[int(pose)]}" if pose is not None else exc.record) from None
    return traj


def write_tum(path: str | Path, traj: Trajectory, inputs: tuple = ()) -> None:
    """Write ``traj`` atomically; times as exact seconds (6 decimals), values in full float64 precision."""
    with atomic_path(path, inputs=inputs) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            write_table(fh, traj.t, np.hstack([traj.position, traj.quat_xyzw]), header="t tx ty tz qx qy qz qw (T_world_cam, t in s)")


def is_tum_file(path: str | Path) -> bool:
    """True if the first data line of ``path`` has 8 numbers (cheap sniff for ``evpose info``)."""
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                s = line.strip()
                if not s or s.startswith("#"):
                    continue
                parts = s.split()
                if len(parts) != 8:
                    return False
                [float(p) for p in parts]
                return True
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return False
