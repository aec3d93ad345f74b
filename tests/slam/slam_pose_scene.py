"""A pinhole, a camera pose from a rotation vector and a random scene in front of it, shared by the SLAM pose tests
(importable by name: tests/slam is on the path pytest gives its test modules; not a test module)."""

import numpy as np
from scipy.spatial.transform import Rotation

K = np.array([[250.0, 0, 173], [0, 250.0, 130], [0, 0, 1]])


def pose(rotvec, t) -> np.ndarray:
    """A 4x4 pose from a rotation vector (rad) and a translation."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    T[:3, 3] = t
    return T


def scene(n: int, seed: int = 0) -> np.ndarray:
    """``n`` points 3-6 m in front of the identity camera, inside its view."""
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-1, 1, n), rng.uniform(-0.8, 0.8, n), rng.uniform(3, 6, n)]
