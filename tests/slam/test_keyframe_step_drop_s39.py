"""The shrinking side of the keyframe step check can act on its own (``TrackingConfig.keyframe_step_drop_action``,
:mod:`evpose.slam.keyframe_step`): skip a keyframe whose step collapsed while the jump side still re-scales."""

from types import SimpleNamespace

import numpy as np

from evpose.io.config_file import config_from_dict, config_to_dict
from evpose.slam.config import SlamConfig
from evpose.slam.keyframe_step import KeyframeStepAction, KeyframeStepDropAction, check_keyframe_step


def _T(x: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, 0.0, 0.0)
    return T


def _kfs():
    """Keyframes every 50 ms at 2 units/s along x."""
    return [SimpleNamespace(id=i, t_us=50000 * i, T_wc=_T(0.1 * i)) for i in range(4)]


def _cfg(drop_action):
    cfg = SlamConfig().tracking
    cfg.keyframe_step_ratio, cfg.keyframe_step_drop_ratio, cfg.keyframe_step_min_age_s = 3.0, 3.0, 0.0
    cfg.keyframe_step_action, cfg.keyframe_step_drop_action = KeyframeStepAction.RESCALE, drop_action
    return cfg


def test_default_is_off_and_follows_the_main_action():
    assert SlamConfig().tracking.keyframe_step_drop_action is KeyframeStepDropAction.SAME
    kfs, T = _kfs(), _T(0.31)  # 0.01 units in 50 ms: a fifth of the reference speed
    ok, out = check_keyframe_step(kfs, 200000, T, 20, _cfg(KeyframeStepDropAction.SAME))
    assert ok and out is not T and np.allclose(out[:3, 3], (0.4, 0.0, 0.0))  # re-scaled like the jump side


def test_drop_side_skips_while_jump_side_rescales():
    kfs, cfg = _kfs(), _cfg(KeyframeStepDropAction.SKIP)
    ok, out = check_keyframe_step(kfs, 200000, _T(0.31), 20, cfg)
    assert not ok  # collapsed step: no keyframe now
    T = _T(0.9)  # 12 units/s: the jump side keeps its own action
    ok, out = check_keyframe_step(kfs, 200000, T, 20, cfg)
    assert ok and np.allclose(out[:3, 3], (0.4, 0.0, 0.0))
    ok, out = check_keyframe_step(kfs, 200000, _T(0.4), 20, cfg)  # on the reference speed: untouched
    assert ok and np.allclose(out[:3, 3], (0.4, 0.0, 0.0))


def test_drop_action_round_trips_through_a_config_file():
    cfg = SlamConfig()
    cfg.tracking.keyframe_step_drop_action = KeyframeStepDropAction.SKIP
    back = config_from_dict(SlamConfig, config_to_dict(cfg))
    assert back.tracking.keyframe_step_drop_action is KeyframeStepDropAction.SKIP
    assert config_from_dict(SlamConfig, config_to_dict(SlamConfig())).tracking.keyframe_step_drop_action is KeyframeStepDropAction.SAME


def test_drop_side_ignores_a_reference_step_of_a_few_ms():
    """A 5 ms previous step is no speed measurement: with ``keyframe_step_drop_min_ref_s`` 0.01 the collapse is not
    judged against it, while the jump side still is."""
    kfs = _kfs()[:3] + [SimpleNamespace(id=3, t_us=105000, T_wc=_T(0.21))]  # newest step: 5 ms, 2 units/s
    cfg = _cfg(KeyframeStepDropAction.SKIP)
    T = _T(0.2105)  # 45 ms later, 0.0005 units: a fortieth of the reference speed
    ok, _ = check_keyframe_step(kfs, 150000, T, 20, cfg)
    assert not ok
    cfg.keyframe_step_drop_min_ref_s = 0.01
    ok, out = check_keyframe_step(kfs, 150000, T, 20, cfg)
    assert ok and out is T
    ok, out = check_keyframe_step(kfs, 150000, _T(0.9), 20, cfg)  # 15 units/s: still re-scaled to 2 units/s
    assert ok and np.allclose(out[:3, 3], (0.3, 0.0, 0.0))


def test_drop_side_ignores_a_short_step_after_a_jump():
    """Landing seed 9's case: the jump side caught a step three times too long, the BA kept it, and the next keyframe's
    step back to the map's speed looked like a collapse against it. With ``keyframe_step_drop_ref_max_ratio`` 3 a
    reference step that itself jumped is no reference for the shrinking side."""
    kfs = _kfs()[:3] + [SimpleNamespace(id=3, t_us=150000, T_wc=_T(0.2 + 0.4))]  # last step 8 units/s after 2
    cfg = _cfg(KeyframeStepDropAction.SKIP)
    T = _T(0.7)  # 2 units/s again: a quarter of the jumped reference
    ok, _ = check_keyframe_step(kfs, 200000, T, 20, cfg)
    assert not ok
    cfg.keyframe_step_drop_ref_max_ratio = 3.0
    ok, out = check_keyframe_step(kfs, 200000, T, 20, cfg)
    assert ok and out is T
    # After a steady reference the shrinking side still acts.
    ok, _ = check_keyframe_step(_kfs(), 200000, _T(0.31), 20, cfg)
    assert not ok


def test_drop_side_ignores_the_two_view_baseline_with_min_keyframes():
    cfg = _cfg(KeyframeStepDropAction.SKIP)
    two = _kfs()[:2]  # the reference step is the two-view start's own baseline
    ok, _ = check_keyframe_step(two, 100000, _T(0.105), 20, cfg)
    assert not ok
    cfg.keyframe_step_drop_min_keyframes = 3
    T = _T(0.105)
    ok, out = check_keyframe_step(two, 100000, T, 20, cfg)
    assert ok and out is T
