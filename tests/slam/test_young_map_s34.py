"""Feeding young maps (session 34): ``TrackingConfig.young_map_s`` (every PnP-placed MCI of a young map is a keyframe
that triangulates with relaxed parallax gates) and ``InitializationConfig.reference_tracks`` (a denser two-view
reference). Both off by default."""

import numpy as np

from evpose.slam import SlamConfig, SlamStatus, run_slam
from evpose.slam.atlas import Keyframe, SlamMap
from evpose.slam.config import TrackingConfig
from evpose.slam.local_map import triangulate_new_points, young_map, young_triangulation
from slam_synthetic import make_recording
from tests.slam.test_local_map import _two_keyframes


def test_off_by_default():
    cfg = SlamConfig()
    assert cfg.tracking.young_map_s == 0.0
    assert cfg.initialization.reference_tracks == 0


def test_a_map_is_young_until_young_map_s_after_its_first_keyframe():
    m = SlamMap(0)
    assert not young_map(m, 0, TrackingConfig(young_map_s=0.2))  # no keyframe yet
    m.keyframes = [Keyframe(0, 1_000_000, np.eye(4))]
    assert young_map(m, 1_150_000, TrackingConfig(young_map_s=0.2))
    assert not young_map(m, 1_250_000, TrackingConfig(young_map_s=0.2))
    assert not young_map(m, 1_050_000, TrackingConfig())  # off


def test_a_young_maps_keyframe_triangulates_a_pair_the_default_gates_refuse():
    # 0.07 m at 5 m: 0.8 deg, under the default per-point (1 deg) and pair (2 deg) gates, over the young ones (0.5).
    cfg = TrackingConfig(young_map_s=0.3)
    m, K, t2p = _two_keyframes(0.07, seed=1)
    assert triangulate_new_points(m, K, m.keyframes[1], t2p, cfg, 1000) == 1000
    m, K, t2p = _two_keyframes(0.07, seed=1)
    yc = young_triangulation(cfg)
    assert (yc.min_triangulation_deg, yc.min_pair_parallax_deg) == (0.5, 0.5)
    nxt = triangulate_new_points(m, K, m.keyframes[1], t2p, yc, 1000)
    assert nxt - 1000 >= 25
    # noise-free observations: the new points land where the scene is
    for t in range(100, 130):
        if t in t2p:
            p = m.points[t2p[t]]
            assert p.created_kf == 1 and 4.4 < p.xyz[2] < 5.6


def _map_runs(young_map_s: float):
    cfg = SlamConfig()
    cfg.tracking.young_map_s = young_map_s
    return run_slam(make_recording(duration_s=0.8, speed=1.0, seed=2), cfg)


def _young_keyframe_flags(run, young_s: float) -> list[bool]:
    """Keyframe flags of the MCIs placed by PnP within ``young_s`` of the two-view reference (the map's first keyframe)."""
    ref, out = None, []
    for r in run.results:
        if "reference set with" in r.reason:
            ref = r.t_us
        elif r.status is SlamStatus.OK and "initialised" not in r.reason and ref is not None and r.t_us - ref < young_s * 1e6:
            out.append(r.keyframe)
    return out


def test_every_pnp_placed_mci_of_a_young_map_is_a_keyframe():
    on, off = _young_keyframe_flags(_map_runs(0.5), 0.5), _young_keyframe_flags(_map_runs(0.0), 0.5)
    assert len(on) >= 3 and all(on)
    assert len(off) >= 3 and not all(off)  # the default keyframe rule skips some


def test_a_map_turning_faster_than_the_rate_gate_is_not_fed():
    m = SlamMap(0)
    m.keyframes = [Keyframe(0, 0, np.eye(4))]
    cfg = TrackingConfig(young_map_s=0.3, young_map_max_rate_dps=40.0)
    T = np.eye(4)
    c, s = np.cos(np.radians(3.0)), np.sin(np.radians(3.0))
    T[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]  # 3 deg about y
    assert young_map(m, 100_000, cfg, T)  # 30 deg/s
    assert not young_map(m, 50_000, cfg, T)  # 60 deg/s
    assert young_map(m, 50_000, cfg)  # no pose given: age only


def test_a_denser_reference_starts_from_more_features():
    def ref_features(n: int) -> int:
        cfg = SlamConfig()
        cfg.initialization.reference_tracks = n
        cfg.initialization.min_matches = 100_000  # never start a map: every reference is set afresh
        run = run_slam(make_recording(duration_s=0.3, speed=1.0, seed=2, n_points=600), cfg)
        counts = [int(r.reason.split("with ")[1].split()[0]) for r in run.results if "reference set with" in r.reason]
        assert counts
        return max(counts)

    base = ref_features(0)
    assert base <= SlamConfig().features.target_tracks
    assert ref_features(300) > base
