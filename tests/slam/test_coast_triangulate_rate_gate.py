"""TrackingConfig.coast_triangulate_max_rate_dps / coast_triangulate_min_map_s: with coast_triangulate off, which
coasted keyframes still triangulate (a slowly turning coast of a map with a long PnP history)."""
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.slam import SlamConfig
from evpose.slam.system_failures import VisualFailureHandling


def _pose(deg: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("y", deg, degrees=True).as_matrix()
    return T


def _ask(rate_dps: float, map_s: float, *, on: bool = False, max_rate: float = 40.0, min_map_s: float = 0.5) -> bool:
    """A map whose trajectory spans ``map_s`` up to its last PnP pose at 1 s, asked at a coasted pose 0.1 s later that
    has turned ``rate_dps`` * 0.1 s since."""
    cfg = SlamConfig()
    cfg.tracking.coast_triangulate = on
    cfg.tracking.coast_triangulate_max_rate_dps = max_rate
    cfg.tracking.coast_triangulate_min_map_s = min_map_s
    t_pnp = 1_000_000
    m = SimpleNamespace(traj_t=[t_pnp - int(map_s * 1e6), t_pnp], traj_T=[np.eye(4), np.eye(4)])
    slam = SimpleNamespace(cfg=cfg, _last_pnp_t=t_pnp)
    return VisualFailureHandling._coast_triangulates(slam, m, t_pnp + 100_000, _pose(rate_dps * 0.1))


def test_coast_triangulate_on_always_triangulates():
    assert _ask(200.0, 0.1, on=True)


def test_a_slow_coast_of_a_mature_map_triangulates_and_a_fast_one_does_not():
    assert _ask(29.0, 2.0)
    assert not _ask(60.0, 2.0)


def test_a_young_map_does_not_triangulate_however_slowly_it_coasts():
    assert not _ask(17.0, 0.3)
    assert _ask(17.0, 0.3, min_map_s=0.0)


@pytest.mark.parametrize("rate", [0.0, 29.0])
def test_off_by_default_no_coasted_keyframe_triangulates(rate):
    assert not _ask(rate, 2.0, max_rate=0.0)
