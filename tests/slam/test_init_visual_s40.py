"""InertialConfig.init_visual: the IMU initialisation over the visually tracked keyframes of the newest segment."""
import numpy as np
import pytest

from evpose.slam.atlas import Keyframe
from evpose.slam.inertial import InertialConfig, initialize_imu
from evpose.slam.inertial_init_visual import InitVisualConfig, initialize_on_visual_keyframes
from slam_synthetic import make_recording

MAP_SCALE = 0.3  # map units per metre of the up-to-scale visual map


@pytest.fixture(scope="module")
def shaken():
    return make_recording(duration_s=2.0, speed=1.0, seed=5, shake=0.08)


def _keyframes(shaken, coast_from_s: float, noise_m: float = 0.0, seed: int = 0):
    """Keyframes every 50 ms over 1.8 s: visually tracked (true poses at MAP_SCALE, plus noise) until ``coast_from_s``,
    then coasted: positions extrapolated at the last visual velocity, as a map the IMU has not reached coasts."""
    gt = shaken.ground_truth
    T = gt.matrices()
    rng = np.random.default_rng(seed)
    kfs = []
    for i, k in enumerate(range(0, 1800, 50)):
        P = T[k].copy()
        P[:3, 3] = (P[:3, 3] + rng.normal(0, noise_m, 3)) * MAP_SCALE
        kfs.append(Keyframe(i, int(gt.t[k]), P, visual=gt.t[k] / 1e6 < coast_from_s))
    vis = [kf for kf in kfs if kf.visual]
    v = (vis[-1].T_wc[:3, 3] - vis[-2].T_wc[:3, 3]) / ((vis[-1].t_us - vis[-2].t_us) / 1e6)
    for kf in kfs:
        if not kf.visual:
            kf.T_wc[:3, 3] = vis[-1].T_wc[:3, 3] + v * (kf.t_us - vis[-1].t_us) / 1e6
    return kfs


def _cfg(**kw):
    return InertialConfig(max_residual_ratio=1.0, init_visual=InitVisualConfig(enabled=True, **kw))


def test_coasted_keyframes_pull_the_whole_map_init_off_and_the_visual_one_is_right(shaken):
    kfs = _keyframes(shaken, coast_from_s=0.9)
    cfg = _cfg()
    full = initialize_imu([k.t_us for k in kfs], [k.T_wc for k in kfs], shaken.imu, np.eye(4), 0, cfg)
    # 0.9 s of coast at constant velocity: the alignment over every keyframe lands 10 % short of the scale.
    assert not (full.ok and abs(full.scale * MAP_SCALE - 1.0) < 0.05)
    res = initialize_on_visual_keyframes(kfs, 0, shaken.imu, np.eye(4), 0, cfg)
    assert res.ok, res.reason
    assert res.scale * MAP_SCALE == pytest.approx(1.0, rel=0.01)
    assert all(kfs[i].visual for i in res.used)
    assert len(res.velocities) == len(res.used)


def test_only_the_newest_segment_is_used(shaken):
    kfs = _keyframes(shaken, coast_from_s=2.0)
    for kf in kfs[:10]:
        kf.T_wc[:3, 3] *= 3.0  # an older re-joined segment at another scale
    res = initialize_on_visual_keyframes(kfs, kfs[10].id, shaken.imu, np.eye(4), 0, _cfg())
    assert res.ok, res.reason
    assert min(res.used) >= 10
    assert res.scale * MAP_SCALE == pytest.approx(1.0, rel=0.02)


def test_refuses_a_short_visual_stretch_and_an_undetermined_scale(shaken):
    short = initialize_on_visual_keyframes(_keyframes(shaken, coast_from_s=0.2), 0, shaken.imu, np.eye(4), 0, _cfg())
    assert not short.ok and "visually tracked" in short.reason
    noisy = _keyframes(shaken, coast_from_s=2.0, noise_m=0.02)
    res = initialize_on_visual_keyframes(noisy, 0, shaken.imu, np.eye(4), 0, _cfg())
    assert not res.ok and "undetermined" in res.reason
    # Without the scale test the same keyframes pass at a scale pulled towards zero (errors in the regressor).
    loose = initialize_on_visual_keyframes(noisy, 0, shaken.imu, np.eye(4), 0, _cfg(max_scale_std_ratio=0.0))
    assert loose.ok and loose.scale * MAP_SCALE < 0.2
    # The standard error does not see a milder bias: 5 mm errors pass the test at 0.68 of the scale (why the indoor
    # maps' 1-8 cm errors cannot be gated into a metric initialisation).
    mild = initialize_on_visual_keyframes(_keyframes(shaken, coast_from_s=2.0, noise_m=0.005), 0, shaken.imu, np.eye(4), 0, _cfg())
    assert mild.ok and mild.scale * MAP_SCALE < 0.8
