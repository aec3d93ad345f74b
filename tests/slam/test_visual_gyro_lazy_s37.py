"""The visual gyro (event-only coasting's measured rotation) is asked only for MCIs the map fails to place."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.slam import EventSlam, SlamConfig, SlamStatus
from evpose.slam.run import run_slam
from slam_synthetic import make_recording


@pytest.fixture(scope="module")
def rec():
    return make_recording(duration_s=0.4, speed=1.5, seed=7, shake=0.08)


def _slam(rec, enabled: bool, monkeypatch, calls: list, measured: np.ndarray | None = None) -> EventSlam:
    cfg = SlamConfig()
    cfg.visual_gyro.enabled = enabled
    slam = EventSlam(cfg, rec.calibration)

    def fake(m, mci):
        calls.append(mci.t_us)
        return measured

    monkeypatch.setattr(slam, "_visual_gyro", fake)
    return slam


def test_tracked_mcis_never_ask_the_visual_gyro(rec, monkeypatch):
    calls: list = []
    slam = _slam(rec, True, monkeypatch, calls)
    results = run_slam(rec, slam.cfg, slam=slam).results
    failed = [r for r in results if r.status in (SlamStatus.COASTING, SlamStatus.LOST)]
    tracked = [r for r in results if r.status is SlamStatus.OK]
    assert len(tracked) >= 3
    # Each call belongs to a failed MCI (a coast or a loss), none to a tracked one.
    assert len(calls) <= len(failed)
    assert not set(calls) & {r.t_us for r in tracked}


def test_a_failed_mci_coasts_on_the_measured_rotation_when_enabled(rec, monkeypatch):
    calls: list = []
    slam = _slam(rec, True, monkeypatch, calls)
    slam.step(rec.events)
    m = slam.atlas.active
    R = m.traj_T[-1][:3, :3] @ Rotation.from_rotvec([0.0, 0.03, 0.0]).as_matrix()
    slam._visual_gyro = lambda m_, mci_: (calls.append(mci_.t_us), R)[1]
    mci = SimpleNamespace(t_us=m.traj_t[-1] + 4000, image8=np.zeros((rec.calibration.height, rec.calibration.width), np.uint8))
    assert slam._coast_rotation(m, mci, None) is R and calls[-1] == mci.t_us
    # A gyro rotation (event-inertial) is never replaced, and without the option nothing is measured.
    R_gyro = np.eye(3)
    assert slam._coast_rotation(m, mci, R_gyro) is R_gyro
    n = len(calls)
    slam.cfg.visual_gyro.enabled = False
    assert slam._coast_rotation(m, mci, None) is None and len(calls) == n
