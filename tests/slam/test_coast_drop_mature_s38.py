"""``TrackingConfig.coast_drop_mature_s``: the coast that ends a mature map (at least this long up to its last PnP pose)
is removed from the map's trajectory; a young map's coast is kept."""
from types import SimpleNamespace

from evpose.slam import SlamConfig, SlamStatus
from evpose.slam.system_failures import VisualFailureHandling
from slam_synthetic import circle_map


class _Sys(VisualFailureHandling):
    """The failure handling alone, on one map: PnP poses every 20 ms up to ``t_pnp``, coasted ones after it."""

    def __init__(self, cfg, n_pnp: int, n_coast: int):
        self.cfg, self.imu, self._state = cfg, None, SlamStatus.COASTING
        self.map = circle_map(n_pnp + n_coast, 20_000)
        self._last_pnp_t = self._last_visual_t = self.map.traj_t[n_pnp - 1]
        self._blank_us, self._after_blank_t = 0, None
        self.atlas = SimpleNamespace(active=self.map, new_map=lambda: None)
        self.fe = SimpleNamespace(track_to_point={1: 2}, init_ref=None)

    def coast_runs_out(self):
        # The next MCI lies past coast_s since the last visual pose: the coast ends in a loss.
        t = self.map.traj_t[-1] + 20_000
        gap_s = (t - self._last_visual_t) / 1e6
        assert gap_s > self.cfg.tracking.coast_s
        return VisualFailureHandling._coast_event_only(self, SimpleNamespace(t_us=t), "0 tracked map points < 12", gap_s)


def _cfg(lim: float) -> SlamConfig:
    cfg = SlamConfig()
    cfg.tracking.coast_drop_mature_s = lim
    return cfg


def test_off_by_default():
    assert SlamConfig().tracking.coast_drop_mature_s == 0.0


def test_a_mature_maps_lost_coast_is_dropped_down_to_its_last_visual_pose():
    s = _Sys(_cfg(0.5), n_pnp=40, n_coast=20)  # 0.78 s of PnP poses, then 0.4 s coasted
    status, reason, T, _ = s.coast_runs_out()
    assert status is SlamStatus.LOST and T is None and reason.startswith("tracking lost")
    assert len(s.map.traj_t) == 40 and s.map.traj_t[-1] == s._last_visual_t
    assert len(s.map.traj_T) == len(s.map.traj_ref) == len(s.map.traj_rel) == 40


def test_a_young_maps_lost_coast_and_the_default_keep_the_coast():
    young = _Sys(_cfg(0.5), n_pnp=20, n_coast=20)  # 0.38 s of PnP poses: younger than the limit
    young.coast_runs_out()
    assert len(young.map.traj_t) == 40
    off = _Sys(SlamConfig(), n_pnp=40, n_coast=20)
    off.coast_runs_out()
    assert len(off.map.traj_t) == 60
