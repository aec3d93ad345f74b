"""The ablation benchmarks' per-seed tables (evpose.bench.fusion_tracking), with the tracking runs replaced."""

from pathlib import Path

import pytest

from evpose.bench import BenchContext
from evpose.bench import fusion_tracking as ft
from evpose.bench import tracking


@pytest.fixture
def fake_runs(monkeypatch):
    calls = []

    def landing_case(work_dir, res, seconds, seed, scenario="landing"):
        return (seed, seconds, res), "map"  # (recording, map) stand-ins

    def ablation_run(recording, contour_map, mode, event_filter=None):
        seed, seconds, _ = recording
        calls.append((seed, seconds, mode))
        return {"ate_rmse_mm": 10.0 * seed + len(mode), "are_rmse_deg": 0.1, "lost_updates": seed}

    monkeypatch.setattr(tracking, "landing_case", landing_case)
    monkeypatch.setattr(ft, "ablation_run", ablation_run)
    return calls


def test_long_ablation_runs_each_mode_on_each_3s_seed_and_reports_means(fake_runs):
    out = ft.bench_ablation_long(BenchContext(quick=False, work_dir=Path("unused"), seed=2))
    seeds = range(2, 2 + ft.ABLATION_SEEDS)
    assert fake_runs == [(s, 3.0, mode) for s in seeds for mode in ("stpe", "full", "full:ekf")]
    per = [10.0 * s + len("full:ekf") for s in seeds]
    assert out["346x260_3s_full_ekf_ate_rmse_mm_per_seed"] == per
    assert out["346x260_3s_full_ekf_ate_rmse_mm_mean"] == pytest.approx(sum(per) / len(per))
    assert out["346x260_3s_stpe_not_ok_updates"] == sum(seeds)
    assert "346x260_3s_full_smoothed_ate_rmse_mm_mean" not in out  # no run reported it


def test_seed_ablation_covers_both_resolutions_with_the_papers_four_modes(fake_runs):
    out = ft.bench_ablation_seeds(BenchContext(quick=False, work_dir=Path("unused")))
    for tag in ("346x260", "240x180"):
        for name in ("stpe", "stpe+filter", "full", "full_ekf"):
            assert len(out[f"{tag}_{name}_ate_rmse_mm_per_seed"]) == ft.ABLATION_SEEDS
    assert len(fake_runs) == 2 * 4 * ft.ABLATION_SEEDS


def test_ablation_tables_are_skipped_in_the_quick_suite(fake_runs):
    ctx = BenchContext(quick=True, work_dir=Path("unused"))
    assert "skipped" in ft.bench_ablation_long(ctx) and "skipped" in ft.bench_ablation_seeds(ctx)
    assert fake_runs == []


def test_ablation_table_reports_the_filters_latency_change_to_the_pose_and_its_free_filter_floor(monkeypatch):
    lat = {"stpe": (0.6, 0.6, 0.45), "stpe+filter": (1.2, 1.1, 0.72)}  # whole front end, to the pose, field + registration

    def ablation_run(recording, contour_map, mode, event_filter=None):
        fe, to_pose, core = lat.get(mode, (1.0, 1.0, 1.0))
        return {"stpe_latency_median_ms": fe, "stpe_latency_to_pose_median_ms": to_pose, "field_registration_median_ms": core}

    monkeypatch.setattr(ft, "ablation_run", ablation_run)
    out = ft._ablation_table("rec", [0] * 5, "346x260", 2.0, with_variants=False)
    assert out["filter_stpe_latency_change_pct"] == pytest.approx(100.0)
    assert out["filter_stpe_latency_to_pose_change_pct"] == pytest.approx(100.0 * 0.5 / 0.6)
    assert out["filter_free_floor_change_pct"] == pytest.approx(20.0)
