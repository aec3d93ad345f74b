"""Registration settings that depend on the sensor (evpose/tracker/registration_config.py)."""

from __future__ import annotations

import pytest
from tracker_synthetic import generate

from evpose.tracker.config import TrackerConfig
from evpose.tracker.modes import MotionComponents
from evpose.tracker.registration_config import RegistrationConfig, prior_widening
from evpose.tracker.tracker import Tracker


def test_the_prior_widens_only_on_sensors_coarser_than_the_reference():
    c = RegistrationConfig()
    ref = c.fused_prior_reference_pixel_mrad
    assert prior_widening(c, ref) == 1.0 and prior_widening(c, 0.5 * ref) == 1.0
    assert prior_widening(c, 1.5 * ref) == pytest.approx(1.5 ** c.fused_prior_pixel_exponent)
    c.fused_prior_pixel_exponent = 1.0
    assert prior_widening(c, 2.0 * ref) == pytest.approx(2.0)
    c.fused_prior_reference_pixel_mrad = 0.0
    assert prior_widening(c, 100.0) == 1.0  # 0 = never


def test_only_the_fused_modes_register_with_the_widened_prior():
    rec, cmap, _ = generate(duration_s=0.1, seed=1)
    cfg = TrackerConfig()
    pixel_mrad = 1e3 / rec.calibration.K[0, 0]
    assert pixel_mrad > cfg.registration.fused_prior_reference_pixel_mrad  # the generated camera is a coarse one
    widen = prior_widening(cfg.registration, pixel_mrad)
    fused = Tracker(cfg, cmap, rec.calibration, components=MotionComponents(drives_pose=True))._registration
    assert fused.prior_rotation_deg == pytest.approx(cfg.registration.prior_rotation_deg * widen)
    assert fused.prior_translation_m == pytest.approx(cfg.registration.prior_translation_m * widen)
    assert cfg.registration.prior_rotation_deg == RegistrationConfig().prior_rotation_deg  # the caller's config untouched
    stpe = Tracker(cfg, cmap, rec.calibration)._registration
    assert (stpe.prior_rotation_deg, stpe.prior_translation_m) == (cfg.registration.prior_rotation_deg,
                                                                  cfg.registration.prior_translation_m)
    cfg.registration.fused_prior_reference_pixel_mrad = 2.0 * pixel_mrad  # a finer sensor than the reference: as given
    fine = Tracker(cfg, cmap, rec.calibration, components=MotionComponents(drives_pose=True))._registration
    assert fine.prior_rotation_deg == cfg.registration.prior_rotation_deg
