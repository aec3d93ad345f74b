"""``InitializationConfig.drop_static_after_s``: ``drop_static_matches`` acts only once the run has gone that long
without a map (since the newest pose of any map, or the recording's start)."""

import numpy as np

from evpose.slam import SlamConfig
from evpose.slam.atlas import Atlas
from evpose.slam.system_initialisation import TwoViewInitialisation


class _Run(TwoViewInitialisation):
    """The two attributes the gate reads, without a whole system."""

    def __init__(self, drop: bool, after_s: float):
        cfg = SlamConfig()
        cfg.initialization.drop_static_matches = drop
        cfg.initialization.drop_static_after_s = after_s
        self._init_cfg = cfg.initialization
        self.atlas = Atlas()
        self.imu = None  # event-only


def _lost_map_at(run: _Run, times_us):
    m = run.atlas.new_map()
    for t in times_us:
        m.add_pose(t, np.eye(4))
    run.atlas.new_map()  # the empty map the next start fills, as EventSlam._lose leaves it


def test_default_waits_a_tenth_of_a_second():
    assert SlamConfig().initialization.drop_static_after_s == 0.1


def test_unmapped_time_counts_from_the_newest_pose_of_any_map_or_the_start():
    run = _Run(True, 0.1)
    assert run._unmapped_s(50_000) == 0.05  # no map yet: since the recording's start
    _lost_map_at(run, [100_000, 200_000, 380_000])
    _lost_map_at(run, [])
    assert np.isclose(run._unmapped_s(430_000), 0.05)
    assert np.isclose(run._unmapped_s(527_000), 0.147)


def test_the_gate_lets_only_a_run_long_without_a_map_drop_still_matches():
    run = _Run(True, 0.1)
    _lost_map_at(run, [100_000, 380_000])
    assert not run._drops_static(430_000)  # the ordinary start gets its chance first
    assert run._drops_static(480_000)
    assert run._drops_static(527_000)
    assert _Run(True, 0.0)._drops_static(1)  # 0: every attempt, as drop_static_matches alone
    off = _Run(False, 0.1)
    _lost_map_at(off, [100_000])
    assert not off._drops_static(900_000)


def test_event_inertial_starts_keep_every_match():
    run = _Run(True, 0.1)
    run.imu = object()  # any IMU stream: E-I-C2/C3
    _lost_map_at(run, [100_000])
    assert not run._drops_static(900_000)
