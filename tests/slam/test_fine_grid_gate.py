"""Which MCIs get the fine-grid KLT (``FeatureConfig.klt_upsample_min_events_per_px``, ``klt_upsample_warmup_mcis``)."""

from dataclasses import replace

from evpose.slam.config import FeatureConfig
from evpose.slam.features import FrontendTracks
from evpose.slam.fine_grid import use_fine_grid

PIXELS = 1000


def _calls(cfg: FeatureConfig, densities: list[float]) -> list[bool]:
    fe = FrontendTracks()
    return [use_fine_grid(fe, int(round(d * PIXELS)), PIXELS, cfg) for d in densities]


def test_no_fine_grid_when_upsampling_is_off_whatever_the_events():
    cfg = replace(FeatureConfig(), klt_upsample=1.0, klt_upsample_min_events_per_px=0.1, klt_upsample_warmup_mcis=2)
    assert _calls(cfg, [0.5] * 5) == [False] * 5


def test_every_mci_gets_the_fine_grid_without_an_event_floor():
    cfg = replace(FeatureConfig(), klt_upsample=2.0, klt_upsample_min_events_per_px=0.0)
    assert _calls(cfg, [0.0, 0.01, 0.5]) == [True] * 3


def test_each_mci_is_judged_by_its_own_events_without_a_warm_up():
    cfg = replace(FeatureConfig(), klt_upsample=2.0, klt_upsample_min_events_per_px=0.1, klt_upsample_warmup_mcis=0)
    assert _calls(cfg, [0.05, 0.1, 0.2, 0.02]) == [False, True, True, False]


def test_warm_up_median_decides_once_for_the_rest_of_the_recording():
    cfg = replace(FeatureConfig(), klt_upsample=2.0, klt_upsample_min_events_per_px=0.1, klt_upsample_warmup_mcis=3)
    # Dense warm-up (median 0.2, one sparse MCI in it): on from the third MCI, and sparse MCIs later keep it on.
    assert _calls(cfg, [0.2, 0.01, 0.3, 0.01, 0.01]) == [False, False, True, True, True]
    # Sparse warm-up (median 0.05): off for good, however dense the recording becomes.
    assert _calls(cfg, [0.05, 0.3, 0.01, 0.5, 0.5]) == [False] * 5


def test_warm_up_state_lives_in_the_front_end_tracks():
    cfg = replace(FeatureConfig(), klt_upsample=2.0, klt_upsample_min_events_per_px=0.1, klt_upsample_warmup_mcis=2)
    fe = FrontendTracks()
    assert not use_fine_grid(fe, 300, PIXELS, cfg)
    assert fe.fine_on is None and fe.fine_density == [0.3]
    assert use_fine_grid(fe, 200, PIXELS, cfg)
    assert fe.fine_on is True
