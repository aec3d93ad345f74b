"""The shrinking side of the keyframe step check can give a young map up (``keyframe_step_drop_action`` ``lose``,
:mod:`evpose.slam.keyframe_step`): a young map whose keyframe step collapsed is lost, an older one is left alone."""

import numpy as np

from evpose.io.config_file import config_from_dict, config_to_dict
from evpose.slam.config import SlamConfig
from evpose.slam.keyframe_step import KeyframeStepAction, KeyframeStepDropAction, check_keyframe_step, keyframe_step_collapse
from tests.slam.test_keyframe_step_drop_s39 import _T, _kfs


def _cfg(drop_action=KeyframeStepDropAction.LOSE, max_age_s=0.3):
    cfg = SlamConfig().tracking
    cfg.keyframe_step_ratio, cfg.keyframe_step_drop_ratio, cfg.keyframe_step_min_age_s = 3.0, 3.0, 0.0
    cfg.keyframe_step_action, cfg.keyframe_step_drop_action = KeyframeStepAction.RESCALE, drop_action
    cfg.keyframe_step_lose_max_age_s = max_age_s
    return cfg


def test_default_never_loses_a_map():
    assert SlamConfig().tracking.keyframe_step_drop_action is KeyframeStepDropAction.SAME
    assert keyframe_step_collapse(_kfs(), 200000, _T(0.31), 20, SlamConfig().tracking) is None
    assert keyframe_step_collapse(_kfs(), 200000, _T(0.31), 20, _cfg(KeyframeStepDropAction.SKIP)) is None


def test_young_map_with_a_collapsed_step_is_lost():
    why = keyframe_step_collapse(_kfs(), 200000, _T(0.31), 20, _cfg())  # a fifth of the reference speed, map 0.2 s old
    assert why is not None and "0.10" in why


def test_on_speed_or_jumping_step_does_not_lose_the_map():
    cfg = _cfg()
    assert keyframe_step_collapse(_kfs(), 200000, _T(0.4), 20, cfg) is None
    assert keyframe_step_collapse(_kfs(), 200000, _T(0.9), 20, cfg) is None  # the jump side re-scales instead
    ok, out = check_keyframe_step(_kfs(), 200000, _T(0.9), 20, cfg)
    assert ok and np.allclose(out[:3, 3], (0.4, 0.0, 0.0))


def test_older_map_keeps_its_collapsed_keyframe_as_it_is():
    cfg = _cfg(max_age_s=0.15)  # the map is 0.2 s old at the candidate
    T = _T(0.31)
    assert keyframe_step_collapse(_kfs(), 200000, T, 20, cfg) is None
    ok, out = check_keyframe_step(_kfs(), 200000, T, 20, cfg)
    assert ok and out is T


def test_lose_action_round_trips_through_a_config_file():
    cfg = SlamConfig()
    cfg.tracking.keyframe_step_drop_action = KeyframeStepDropAction.LOSE
    cfg.tracking.keyframe_step_lose_max_age_s = 0.2
    back = config_from_dict(SlamConfig, config_to_dict(cfg)).tracking
    assert back.keyframe_step_drop_action is KeyframeStepDropAction.LOSE and back.keyframe_step_lose_max_age_s == 0.2
