"""The ``full_filter_cost`` benchmark (evpose.bench.filter_registration_cost): the stages it reads, the filter's change
of their medians, and a short ``full`` run with and without the polarity filter that reports them."""

import dataclasses
import time

import pytest

from evpose.bench import filter_registration_cost as fc


def test_stages_split_the_registration_block_into_the_field_and_the_events_and_add_the_filters_own():
    t = {"polarity_predict": 0.2, "polarity_align": 0.4, "distance_field": 0.15, "registration": 1.0, "event_registration": 0.45,
         "polarity_observe": 0.07, "fusion": 0.8, "culling": 0.3}
    s = fc.stage_times(t)
    assert s["registration_to_pose"] == pytest.approx(0.2 + 0.4 + 0.15 + 1.0)  # not the labelling after the pose, nor the fusion
    assert s["registrations"] == pytest.approx(1.0)
    assert s["field_registration"] == pytest.approx(0.55) and s["event_registration"] == pytest.approx(0.45)
    assert fc.stage_times({"distance_field": 0.3, "registration": 0.9, "ego_motion": 0.7})["registration_to_pose"] == pytest.approx(1.9)


def test_the_change_is_the_filters_median_against_the_unfiltered_median():
    stages = {"filter": {"registration_to_pose": [2.0, 2.2, 1.8], "registrations": [1.1, 1.0, 1.2], "event_registration": [0.5] * 3,
                         "distance_field": [0.2] * 3},
              "no_filter": {"registration_to_pose": [1.6, 1.5, 1.4], "registrations": [1.0, 1.0, 1.0], "event_registration": [0.4] * 3,
                            "distance_field": [0.4] * 3}}
    out = fc.change_table(stages)
    assert out["filter_registration_to_pose_median_ms"] == pytest.approx(2.0)
    assert out["full_filter_registration_latency_change_pct"] == pytest.approx(100.0 * (2.0 - 1.5) / 1.5)
    assert out["full_filter_registrations_change_pct"] == pytest.approx(10.0)
    assert out["full_filter_event_registration_change_pct"] == pytest.approx(25.0)
    assert out["full_filter_distance_field_change_pct"] == pytest.approx(-50.0)
    assert "no_filter_registrations_p95_ms" in out


def test_the_stage_clock_is_this_threads_cpu_inside_and_the_wall_clock_after():
    wall = time.perf_counter
    with fc.stage_cpu_clock():
        assert time.perf_counter is time.thread_time
    assert time.perf_counter is wall


def test_full_with_and_without_the_filter_reports_the_change_the_events_and_each_states_accuracy(sim_landing_small):
    from evpose.bench.registration_bias import true_edge_map

    rec = sim_landing_small.recording
    t0 = int(rec.events.t[0])
    rec = dataclasses.replace(rec, events=rec.events.time_window(t0, t0 + 250_000))
    cmap = true_edge_map(sim_landing_small.edges, 0.02)[0]
    out = fc.filter_cost_runs(rec, cmap, rounds=1)
    on, off = out["filter_registration_to_pose_median_ms"], out["no_filter_registration_to_pose_median_ms"]
    assert out["full_filter_registration_latency_change_pct"] == pytest.approx(100.0 * (on - off) / off)
    for state in ("filter", "no_filter"):
        assert out[f"{state}_ate_rmse_mm"] < 50.0
        assert out[f"{state}_events_kept_per_update"] > 0
        assert 0 < out[f"{state}_events_registered_per_update"] <= out[f"{state}_events_kept_per_update"]
    assert 0.0 < out["filter_events_removed_share"] < 1.0
    assert "no_filter_events_removed_share" not in out  # no T_align without the filter
