"""The fusion-regimes benchmark (evpose.bench.fusion_regimes): cold starts, outages, and the paired table."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evpose.bench import BenchContext, collect
from evpose.bench import fusion_regimes as fr
from evpose.core.contour_map import ContourMap


@pytest.fixture(scope="module")
def short_landing(sim_landing_small):
    """The first 0.4 s of the small simulated landing and a map sampled along its true edges (2 cm)."""
    res = sim_landing_small
    rec = res.recording
    pts = [a + (b - a) * (np.arange(max(int(np.linalg.norm(b - a) / 0.02), 1)) / max(int(np.linalg.norm(b - a) / 0.02), 1))[:, None]
           for a, b in res.edges]
    short = dataclasses.replace(rec, events=rec.events.time_window(int(rec.events.t[0]), int(rec.events.t[0]) + 400_000))
    return short, ContourMap.from_points(np.concatenate(pts))


def test_the_cold_start_pose_is_off_by_exactly_the_offsets_and_seeded():
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_matrix()
    T[:3, 3] = (1.0, 2.0, 3.0)
    P = fr.perturbed_pose(T, 0.03, 1.0, seed=4)
    assert np.linalg.norm(P[:3, 3] - T[:3, 3]) == pytest.approx(0.03)
    assert np.degrees(Rotation.from_matrix(P[:3, :3] @ T[:3, :3].T).magnitude()) == pytest.approx(1.0)
    assert np.array_equal(P, fr.perturbed_pose(T, 0.03, 1.0, seed=4))
    assert not np.array_equal(P, fr.perturbed_pose(T, 0.03, 1.0, seed=5))


def test_an_outage_withholds_every_registration_inside_it_and_tracking_resumes_after(short_landing):
    rec, cmap = short_landing
    regime = fr.Regime("outage", outage_start_s=0.15, outage_s=0.1)
    out = fr.regime_run(rec, cmap, regime, "ekf")
    # 20 updates at 200 Hz inside the outage, each reported DEGRADED; the registrations after it are taken again.
    assert out["not_ok_updates"] >= 20
    assert out["not_ok_updates"] < out["updates"] - 20
    for phase in ("outage", "reacquired", "after"):
        assert np.isfinite(out[f"{phase}_ate_rmse_mm"]) and np.isfinite(out[f"{phase}_are_rmse_deg"])
    assert out["outage_end_error_mm"] > 0
    steady = fr.regime_run(rec, cmap, fr.Regime("steady"), "ekf")
    assert steady["not_ok_updates"] < out["not_ok_updates"] and "outage_ate_rmse_mm" not in steady


def test_the_table_pairs_the_backends_per_seed(monkeypatch):
    def regime_run(rec, cmap, regime, backend, seed, config=None, same_inputs=False):
        ate = seed + (0.5 if backend == "ekf" else 0.0) * (-1) ** seed + (1000.0 if (seed, backend) == (4, "ekf") else 0.0)
        return {"ate_rmse_mm": ate, "not_ok_updates": 0, "diverged": int(ate > fr.DIVERGED_MM)}

    monkeypatch.setattr(fr, "regime_run", regime_run)
    out = fr.regime_table([(s, None, None) for s in range(5)], regimes=(fr.Regime("steady"),))
    assert out["steady_factor_graph_ate_rmse_mm_per_seed"] == [0.0, 1.0, 2.0, 3.0, 4.0]
    assert out["steady_ekf_diverged_mean"] == pytest.approx(0.2) and out["steady_factor_graph_diverged_mean"] == 0
    # Seed 4, where the EKF lost the track, is left out of the pairs.
    assert out["steady_seeds_neither_diverged"] == 4
    assert out["steady_graph_minus_ekf_ate_rmse_mm_mean"] == pytest.approx(0.0)
    assert out["steady_graph_wins_ate_rmse_mm"] == 2  # seeds 0 and 2, where the EKF's figure is 0.5 higher
    assert "steady_graph_wins_not_ok_updates" not in out


def test_the_benchmark_is_registered_under_fusion(monkeypatch):
    assert collect()["fusion.regimes"] is fr.bench_fusion_regimes
    calls = []
    monkeypatch.setattr("evpose.bench.tracking.landing_case", lambda work_dir, res, seconds, seed: calls.append((res, seconds, seed)) or (seed, None))
    monkeypatch.setattr(fr, "regime_table", lambda cases, regimes, same_inputs: {"n": len(list(cases)), "regimes": [r.name for r in regimes]})
    out = fr.bench_fusion_regimes(BenchContext(quick=True, work_dir=Path("unused"), seed=3))
    assert out["240x180_n"] == 1 and calls == [((240, 180), 2.0, 3)]
    assert out["240x180_regimes"] == list(fr.QUICK_REGIMES)


def test_the_outlier_regime_moves_every_nth_registration_by_exactly_its_offsets_and_passes_failures_through():
    calls = []
    regime = fr.Regime("outliers", outlier_every=3, outlier_m=0.03, outlier_deg=1.0)
    report = fr.altered_report(lambda t, T, cov: calls.append((t, T, cov)), regime, 0, 0, seed=2)
    T = np.eye(4)
    cov = np.eye(6)
    for t in range(7):
        report(t, T, cov)
    report(7, None, None)  # a failed registration is passed on and not counted
    report(8, T, cov)
    report(9, T, cov)
    moved = [t for t, P, _ in calls if P is not None and not np.array_equal(P, T)]
    assert moved == [2, 5, 9]
    for t, P, c in calls:
        if t in moved:
            assert np.linalg.norm(P[:3, 3]) == pytest.approx(0.03)
            assert np.degrees(Rotation.from_matrix(P[:3, :3]).magnitude()) == pytest.approx(1.0)
            assert c is cov
    assert calls[7] == (7, None, None)


def test_an_outage_report_withholds_only_inside_its_window():
    calls = []
    regime = fr.Regime("outage", outage_start_s=0.1, outage_s=0.1)
    report = fr.altered_report(lambda t, T, cov: calls.append(T is None), regime, 100, 200, seed=0)
    for t in (50, 100, 199, 200):
        report(t, np.eye(4), np.eye(6))
    assert calls == [False, True, True, False]


def test_the_same_inputs_replay_gives_the_estimators_own_gap_without_the_closed_loop(short_landing):
    rec, cmap = short_landing
    out = fr.regime_run(rec, cmap, fr.Regime("steady"), "factor_graph", same_inputs=True)
    # Both estimators on the graph run's own registrations: they differ by far less than either's error.
    assert 0 < out["same_inputs_gap_mm"] < 0.2 * out["ate_rmse_mm"]
    assert abs(out["same_inputs_graph_minus_ekf_ate_mm"]) <= out["same_inputs_gap_mm"] + 1e-9
    assert np.isfinite(out["same_inputs_graph_minus_ekf_are_deg"])
    # The window's corrected states have seen later registrations, which the filter never revisits.
    assert out["same_inputs_corrected_minus_ekf_ate_mm"] < 0 and np.isfinite(out["same_inputs_corrected_minus_ekf_are_deg"])
    assert "same_inputs_gap_mm" not in fr.regime_run(rec, cmap, fr.Regime("steady"), "factor_graph")
