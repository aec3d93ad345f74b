"""A keyframe whose step is a multiple of its map's recent keyframe speed is skipped or re-scaled
(``TrackingConfig.keyframe_step_ratio``, :mod:`evpose.slam.keyframe_step`)."""

from types import SimpleNamespace

import numpy as np

from evpose.io.config_file import config_from_dict, config_to_dict
from evpose.slam.config import SlamConfig
from evpose.slam.keyframe_step import (KeyframeStepAction, check_keyframe_step, keyframe_step_ratio,
                                       reference_step_speed)


def _T(x: float, y: float = 0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, 0.0)
    return T


def _kfs():
    """Keyframes every 50 ms moving +1 unit/s along x, the last step at 2 units/s."""
    xs = [0.0, 0.05, 0.10, 0.20]
    return [SimpleNamespace(id=i, t_us=50000 * i, T_wc=_T(x)) for i, x in enumerate(xs)]


def _cfg(ratio: float, action=KeyframeStepAction.RESCALE, max_inliers: int = 0, steps: int = 1, drop: float = 0.0,
         min_age_s: float = 0.0):
    cfg = SlamConfig().tracking
    cfg.keyframe_step_ratio, cfg.keyframe_step_action = ratio, action
    cfg.keyframe_step_drop_ratio, cfg.keyframe_step_min_age_s = drop, min_age_s
    cfg.keyframe_step_max_inliers, cfg.keyframe_step_ref_steps = max_inliers, steps
    return cfg


def test_reference_is_the_newest_steps_speed():
    kfs = _kfs()
    assert abs(reference_step_speed(kfs, 1) - 2.0) < 1e-9
    assert abs(reference_step_speed(kfs, 3) - 0.2 / 0.15) < 1e-9
    # A step over 0.15 s apart ends the run of steps; none at all gives no reference.
    gap = kfs[:3] + [SimpleNamespace(id=9, t_us=300000, T_wc=_T(0.5))]
    assert reference_step_speed(gap, 3) is None
    assert reference_step_speed(kfs[:1], 1) is None


def test_ratio_is_the_candidate_step_speed_over_the_reference():
    kfs = _kfs()
    r, v = keyframe_step_ratio(kfs, 200000, _T(0.5), 1)  # 0.3 units in 50 ms = 6 units/s against 2
    assert abs(r - 3.0) < 1e-9 and abs(v - 2.0) < 1e-9
    assert keyframe_step_ratio(kfs, 150000, _T(0.5), 1) is None  # no time since the last keyframe
    assert keyframe_step_ratio(kfs, 400000, _T(0.5), 1) is None  # too long after it to be a speed


def test_off_at_ratio_one_and_within_the_limit_nothing_changes():
    kfs, T = _kfs(), _T(0.8)  # 12 units/s: six times the reference
    ok, out = check_keyframe_step(kfs, 200000, T, 20, _cfg(1.0))
    assert ok and out is T
    # The defaults (3, jump side, rescale) judge it.
    ok, out = check_keyframe_step(kfs, 200000, T, 20, SlamConfig().tracking)
    assert ok and out is not T and np.allclose(out[:3, 3], (0.3, 0.0, 0.0))
    ok, out = check_keyframe_step(kfs, 200000, _T(0.3), 20, _cfg(3.0))  # 2 units/s: ratio 1
    assert ok and np.array_equal(out, _T(0.3))
    ok, out = check_keyframe_step(kfs, 200000, _T(0.24), 20, _cfg(3.0))  # 0.8 units/s: ratio 0.4 > 1 / 3
    assert ok and np.array_equal(out, _T(0.24))


def test_a_jumping_keyframe_is_rescaled_along_its_own_direction():
    kfs = _kfs()
    T = _T(0.5, 0.4)  # step (0.3, 0.4): length 0.5 in 50 ms = 10 units/s, five times the reference
    T[:3, :3] = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    ok, out = check_keyframe_step(kfs, 200000, T, 20, _cfg(3.0))
    assert ok and out is not T
    # The step now has the reference's length (2 units/s * 50 ms = 0.1) and the candidate's direction; rotation kept.
    assert np.allclose(out[:3, 3], (0.2 + 0.06, 0.08, 0.0))
    assert np.array_equal(out[:3, :3], T[:3, :3])
    # A collapsing step (a twentieth of the reference) is kept unless the drop side is on, then stretched to it.
    ok, out = check_keyframe_step(kfs, 200000, _T(0.205), 20, _cfg(3.0))
    assert ok and np.array_equal(out, _T(0.205))
    ok, out = check_keyframe_step(kfs, 200000, _T(0.205), 20, _cfg(3.0, drop=3.0))
    assert ok and np.allclose(out[:3, 3], (0.3, 0.0, 0.0))


def test_young_maps_are_not_judged():
    kfs, T = _kfs(), _T(0.8)  # the candidate is 0.2 s after the map's first keyframe
    assert check_keyframe_step(kfs, 200000, T, 20, _cfg(3.0, min_age_s=0.25))[1] is T
    assert check_keyframe_step(kfs, 200000, T, 20, _cfg(3.0, min_age_s=0.2))[1] is not T


def test_skip_and_the_inlier_gate():
    kfs, T = _kfs(), _T(0.8)
    ok, out = check_keyframe_step(kfs, 200000, T, 20, _cfg(3.0, KeyframeStepAction.SKIP))
    assert not ok and out is T
    # With more inliers than keyframe_step_max_inliers the step counts as observed: kept as it is.
    ok, out = check_keyframe_step(kfs, 200000, T, 40, _cfg(3.0, KeyframeStepAction.SKIP, max_inliers=30))
    assert ok and out is T
    ok, out = check_keyframe_step(kfs, 200000, T, 30, _cfg(3.0, KeyframeStepAction.SKIP, max_inliers=30))
    assert not ok


def test_config_round_trip_keeps_the_action():
    cfg = SlamConfig()
    cfg.tracking.keyframe_step_ratio = 3.0
    cfg.tracking.keyframe_step_action = KeyframeStepAction.SKIP
    back = config_from_dict(SlamConfig, config_to_dict(cfg))
    assert back.tracking.keyframe_step_ratio == 3.0 and back.tracking.keyframe_step_action is KeyframeStepAction.SKIP


def test_the_slam_system_consults_the_check_event_only(monkeypatch):
    # End to end on the tiny synthetic recording (its keyframes are too far apart in time for a speed reading, so
    # the check itself is stood in for): a keyframe the check refuses is not made, a re-scaled pose is the one used.
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parent))
    from slam_synthetic import make_recording
    import evpose.slam.system as system
    from evpose.slam.run import run_slam

    rec = make_recording(duration_s=0.8, speed=1.5, seed=7, shake=0.08)
    n_default = sum(1 for r in run_slam(rec, SlamConfig()).results if r.keyframe)
    calls = []

    def refuse(kfs, t_us, T_wc, n_inliers, cfg):
        calls.append((len(kfs), n_inliers, cfg.keyframe_step_ratio))
        return False, T_wc

    monkeypatch.setattr(system, "check_keyframe_step", refuse)
    n_refused = sum(1 for r in run_slam(rec, SlamConfig()).results if r.keyframe)
    assert n_default > 0 and n_refused == 0 and calls
    assert all(k >= 2 and n >= 12 and ratio == 3.0 for k, n, ratio in calls)
