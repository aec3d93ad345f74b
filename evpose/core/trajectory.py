"""Pose trajectories: timestamps plus ``T_world_cam`` (camera-to-world) poses."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from evpose.core.timestamps import check_series, window_slice
from evpose.errors import InputError


def pose_matrix(rotation: Rotation, position: np.ndarray) -> np.ndarray:
    """Stack rotations and translations into (N, 4, 4) homogeneous matrices."""
    mats = rotation.as_matrix().reshape(-1, 3, 3)
    n = mats.shape[0]
    out = np.zeros((n, 4, 4))
    out[:, :3, :3] = mats
    out[:, :3, 3] = np.asarray(position, dtype=np.float64).reshape(n, 3)
    out[:, 3, 3] = 1.0
    return out


def invert_pose(T: np.ndarray) -> np.ndarray:
    """Inverse of one (4, 4) or many (N, 4, 4) rigid transforms."""
    T = np.asarray(T, dtype=np.float64)
    R = T[..., :3, :3]
    t = T[..., :3, 3]
    out = np.zeros_like(T)
    Rt = np.swapaxes(R, -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, t)
    out[..., 3, 3] = 1.0
    return out


MAX_COORDINATE_M = 1e7
"""Largest coordinate magnitude a map, cloud or trajectory may have, metres (beyond the Earth's radius: not metres, or
garbage; 1e300 overflowed the KD-tree of a map with a traceback, and evo's alignment of a trajectory with numpy's warnings)."""


def skew(w: np.ndarray) -> np.ndarray:
    """The 3x3 cross-product matrix of ``w`` (``skew(w) @ v == cross(w, v)``)."""
    x, y, z = np.asarray(w, dtype=np.float64).tolist()  # Python floats: the same values, a third of the indexing cost
    return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))


def quaternion_problem(quat_xyzw: np.ndarray) -> tuple[int, str] | None:
    """(index, problem) of the first quaternion that cannot be normalised, or None; NaNs are left to ``validate``.

    ``np.linalg.norm`` overflows on a component of 1e300 (numpy's warning on stderr, and the quaternion normalised to
    zeros); readers call this before :meth:`Trajectory.from_arrays` to name the record with the problem."""
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.linalg.norm(quat_xyzw, axis=1)
    bad = np.flatnonzero((norms < 1e-9) | (norms == np.inf))
    if not bad.size:
        return None
    i = int(bad[0])
    return i, "quaternion has zero length" if norms[i] < 1e-9 else "quaternion's length is beyond the float range"


@dataclass(frozen=True)
class Trajectory:
    """Time-stamped poses ``T_world_cam`` (maps camera-frame points into the world)."""

    t: np.ndarray
    """Timestamps, int64 microseconds, strictly increasing."""
    position: np.ndarray
    """Camera centre in the world, float64 (N, 3), metres."""
    quat_xyzw: np.ndarray
    """Orientation of the camera in the world as unit quaternions (x, y, z, w), float64 (N, 4)."""

    @classmethod
    def from_arrays(cls, t, position, quat_xyzw) -> "Trajectory":
        t = np.ascontiguousarray(t, dtype=np.int64)
        position = np.ascontiguousarray(position, dtype=np.float64).reshape(-1, 3)
        q = np.ascontiguousarray(quat_xyzw, dtype=np.float64).reshape(-1, 4)
        if not (t.shape[0] == position.shape[0] == q.shape[0]):
            raise ValueError("trajectory columns differ in length")
        # A NaN or infinite quaternion (caught by ``validate`` with its record) must not print numpy warnings first.
        with np.errstate(invalid="ignore", over="ignore"):
            norms = np.linalg.norm(q, axis=1, keepdims=True)
            q = q / np.where(norms > 0, norms, 1.0)
        return cls(t, position, q)

    @classmethod
    def from_matrices(cls, t, T_world_cam: np.ndarray) -> "Trajectory":
        T = np.asarray(T_world_cam, dtype=np.float64).reshape(-1, 4, 4)
        q = Rotation.from_matrix(T[:, :3, :3]).as_quat()
        return cls.from_arrays(t, T[:, :3, 3], q)

    @classmethod
    def empty(cls) -> "Trajectory":
        return cls.from_arrays(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 4)))

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __getitem__(self, index) -> "Trajectory":
        return Trajectory(self.t[index], self.position[index], self.quat_xyzw[index])

    @property
    def rotation(self) -> Rotation:
        return Rotation.from_quat(self.quat_xyzw)

    def matrices(self) -> np.ndarray:
        """All poses as (N, 4, 4) ``T_world_cam`` matrices."""
        return pose_matrix(self.rotation, self.position)

    def matrix(self, i: int) -> np.ndarray:
        return pose_matrix(Rotation.from_quat(self.quat_xyzw[i]), self.position[i])[0]

    def interpolate(self, t_query_us) -> "Trajectory":
        """Poses at the given times: linear in position, slerp in rotation; times are clamped to the span."""
        tq = np.atleast_1d(np.asarray(t_query_us, dtype=np.int64))
        if len(self) == 0:
            raise ValueError("cannot interpolate an empty trajectory")
        if len(self) == 1:
            return Trajectory.from_arrays(tq, np.repeat(self.position, tq.size, 0), np.repeat(self.quat_xyzw, tq.size, 0))
        tc = np.clip(tq, self.t[0], self.t[-1]).astype(np.float64)
        ts = self.t.astype(np.float64)
        pos = np.stack([np.interp(tc, ts, self.position[:, k]) for k in range(3)], axis=1)
        rot = Slerp(ts, self.rotation)(tc)
        return Trajectory.from_arrays(tq, pos, rot.as_quat())

    def time_window(self, t0_us: int, t1_us: int) -> "Trajectory":
        return self[window_slice(self.t, t0_us, t1_us)]

    def validate(self, source: str | None = None) -> None:
        if len(self) == 0:
            return
        check_series(self.t, np.isfinite(self.position).all(axis=1) & np.isfinite(self.quat_xyzw).all(axis=1), source, "pose")
        bad = np.flatnonzero(np.abs(self.position).max(axis=1) > MAX_COORDINATE_M)
        if bad.size:
            raise InputError(source, f"position {self.position[bad[0]].tolist()} is beyond {MAX_COORDINATE_M:g} m (not metres?)", f"pose {int(bad[0])}")
        # from_arrays normalised every quaternion; one that is not unit now had zero length or a length beyond the
        # float range (1e300: the norm overflowed), and scipy's Rotation then failed with a traceback.
        bad = np.flatnonzero(np.abs(np.einsum("ij,ij->i", self.quat_xyzw, self.quat_xyzw) - 1.0) > 1e-6)
        if bad.size:
            raise InputError(source, "quaternion has zero length or one beyond the float range", f"pose {int(bad[0])}")
