"""The read-out's compiled mean revision (session 43) equals the gtsam / numpy loop it replaced to rounding."""

import gtsam
import numpy as np

from evpose.fusion.revision_readout import _mean_revision


def test_mean_revision_equals_the_gtsam_loop_to_rounding():
    rng = np.random.default_rng(5)
    T_imu_cam = gtsam.Pose3.Expmap(rng.normal(size=6)).matrix()
    for n in (1, 3, 7):
        now = np.array([gtsam.Pose3.Expmap(rng.normal(size=6)).matrix() for _ in range(n)])
        # As written: the camera poses now, moved by revisions of a few mrad / mm.
        then = np.array([(gtsam.Pose3(mat=m @ T_imu_cam) * gtsam.Pose3.Expmap(rng.normal(size=6) * 3e-3)).matrix() for m in now])
        rotation, position = np.zeros(3), np.zeros(3)
        for m, t in zip(now, then):
            c = m @ T_imu_cam
            rotation += gtsam.Rot3.Logmap(gtsam.Rot3(c[:3, :3] @ t[:3, :3].T))
            position += c[:3, 3] - t[:3, 3]
        out = np.empty(6)
        _mean_revision(now, T_imu_cam, then, out)
        assert np.abs(rotation / n).max() > 1e-4 and np.abs(position / n).max() > 1e-4
        assert np.allclose(out[:3], rotation / n, rtol=1e-11, atol=1e-17)
        assert np.allclose(out[3:], position / n, rtol=1e-11, atol=1e-16)
