"""``full_filter_cost``: what the polarity filter does to the registration cost of ``full`` (issue 7, the paper's
"the filter cuts registration latency by >= 40 %").

The ``ablation`` benchmark reads that claim as ``stpe+filter`` against ``stpe`` (``filter_stpe_latency_change_pct``).
In ``full`` the pose also comes from the step's events registered at their own timestamps
(:mod:`evpose.tracker.event_registration`), a stage whose cost follows the events, and the polarity filter decides
which events the field shows and which of them the events' association may take (a point predicted to fire one
polarity takes no event of the other). So here ``full`` runs with the filter (the defaults) and without it
(``polarity.enabled`` off: no prediction, no ``T_align``, the combined field, events of either polarity), alternated
over rounds in one process on the same recording, and per update (this thread's CPU, the tracker's stage clock
swapped for ``time.thread_time`` during the runs) it reports:

* ``registration_to_pose``: every stage the filter is or feeds before the pose, i.e. the ego-motion filter (off by
  default), the polarity prediction, ``T_align``, the distance field, the field registration and the events'
  registration (``full``'s ``stpe_latency_to_pose`` of ``ablation``);
* ``registrations``: the field registration and the events' registration alone (the filter's own stages free);
  ``field_registration`` and ``event_registration`` each;
* the events the noise filters kept (``events_kept``, what enters the events' association) and those associated
  (``events_registered``) per update, and each state's ATE / ARE (the comparison is honest only beside them).

``full_filter_registration_latency_change_pct`` is 100 x (the median ``registration_to_pose`` with the filter over
the one without, minus 1): the target asks for <= -40. ``full_filter_registrations_change_pct`` and
``full_filter_event_registration_change_pct`` are the same of ``registrations`` and ``event_registration``.

Measured (session 31, ``/tmp/s31/lat31/flat.py`` with the same stages; 346x260 2 s landing from ground truth, built
map, CPU per update, medians / p95 over 4 alternated rounds at load 4.4-5.8 (seed 1: 6-8)):

=====================================  =================  =================  =================
                                       textured, seed 0   plain, seed 0      plain, seed 1
=====================================  =================  =================  =================
``registration_to_pose`` filter / not  2.048 / 1.516 ms   1.850 / 1.204 ms   2.016 / 1.386 ms
  change (the target: <= -40 %)        **+35.1 %**        **+53.7 %**        **+45.5 %**
  p95 filter / not                     2.850 / 2.306      2.626 / 1.953      2.964 / 2.297
``registrations`` (field + events)     1.165 / 1.141 ms   1.043 / 0.952 ms   1.161 / 1.094 ms
  change                               +2.1 %             +9.5 %             +6.1 %
``field_registration``                 0.634 / 0.574      0.570 / 0.482      0.649 / 0.573
``event_registration``                 0.511 / 0.516 ms   0.449 / 0.439 ms   0.483 / 0.479 ms
  change                               -1.1 %             +2.2 %             +0.7 %
distance field                         0.187 / 0.359 ms   0.176 / 0.249 ms   0.184 / 0.285 ms
  change                               -47.8 %            -29.4 %            -35.3 %
the filter's own: prediction, T_align  0.160, 0.486 ms    0.153, 0.435 ms    0.165, 0.457 ms
events kept (both), associated         3402; 878 / 902    1293; 861 / 878    1295; 899 / 910
events ``T_align`` removed             64.8 %             14.8 %             14.2 %
ATE filter / not (ARE deg)             5.18 / 6.72 mm     5.87 / 5.06 mm     5.44 / 5.64 mm
                                       (0.049 / 0.072)    (0.064 / 0.052)    (0.060 / 0.061)
=====================================  =================  =================  =================

So in ``full`` too the filter does not cut the registration's cost: it adds 35-54 % to the stages before the pose.
It makes the field cheaper (-29 to -48 %: one slot over its patches instead of the combined field over the box), but
its own prediction and ``T_align`` (0.59-0.65 ms) cost more than the whole field, and the registrations themselves
stay level: the field registration +10-18 % (fewer iterations, 2.5-2.7 against 3.2-3.6, but the polarity trails and
tangents per point), the events' registration within +-2 %. The events the filter removes never reached the events'
passes: an event is associated only within ``association_radius_px`` (2 px) of a used point's projection, which
already leaves out the texture's events off the map's edges; the filter's polarity test drops only 1.2-2.6 % of the
associated events (the noise filters' ``events_kept`` is the same in both states; the ego-motion filter, off by
default, would take 2 / 9 % of them for 0.72 / 1.34 ms). Against the old reading (``stpe+filter`` against ``stpe``,
``ablation``: +83-91 % in session 30, its field and registration alone 1.07-1.09x ``stpe``'s whole front end) this
one is less far off, and the filter pays for itself in accuracy where the map explains few events (textured seeds
0-2, ``/tmp/s31/lat31/texacc.py``: 5.18 / 7.19 / 6.28 mm with the filter against 6.72 / 9.56 / 7.63 without, mean 6.21
against 7.97); on the plain landing, seeds 0-11 (``/tmp/s31/lat31/run.py``), 4.625 mm with the filter against 4.730
without (paired -0.11 +- 0.13 mm, 8 of 12 better with it). The quick suite (240x180 1 s, one round): +58.4 %. Per-point polarity fields instead of ``T_align``
(``polarity.event_filter`` off) cost more still (2.469 / 2.043 ms, their field 0.98 / 0.70 ms, ATE 7.49 / 8.09 mm).
Inside the registration block the filter's polarities also cost the grazing OFF trails, 0.056 ms per update (their
kernel 0.025-0.028 ms, the rest numpy and Python; prefetching the map's normals 8 points ahead took the kernel to
0.025 ms, not kept: ``/tmp/s31/lat31/grazpf.py``). Nothing the filter removes is processed before being dropped
except by the association's cheap test (see :mod:`evpose.tracker.event_registration`, session 31, for a gate tried
before it).
"""

from __future__ import annotations

import contextlib
import time

import numpy as np

from evpose.bench.stats import latency_summary

STATES = (("filter", True), ("no_filter", False))
"""(name, ``polarity.enabled``) of the two ``full`` runs."""

TO_POSE = ("ego_motion", "polarity_predict", "polarity_align", "distance_field", "registration")
"""The tracker's stages up to the pose that the filter is or feeds (``registration`` holds both registrations)."""

def stage_times(timings_ms: dict) -> dict[str, float]:
    """The stages this benchmark reports, from one update's ``StepResult.timings_ms``."""
    reg = float(timings_ms.get("registration", 0.0))
    event = float(timings_ms.get("event_registration", 0.0))
    return {"registration_to_pose": float(sum(timings_ms.get(m, 0.0) for m in TO_POSE)), "registrations": reg,
            "field_registration": reg - event, "event_registration": event,
            "distance_field": float(timings_ms.get("distance_field", 0.0))}


def change_table(stages: dict[str, dict[str, list[float]]]) -> dict:
    """Medians and p95 of each state's per-update stage samples (``stages[state][stage]``, ms) and the filter's
    change of the medians, percent (negative: the filter makes it cheaper)."""
    out: dict = {}
    for state, per in stages.items():
        for stage, samples in per.items():
            s = latency_summary(samples, f"{state}_{stage}_")
            out.update({k: v for k, v in s.items() if k.endswith(("median_ms", "p95_ms"))})
    for stage, key in (("registration_to_pose", "registration_latency"), ("registrations", "registrations"),
                       ("event_registration", "event_registration"), ("distance_field", "distance_field")):
        on, off = out.get(f"filter_{stage}_median_ms"), out.get(f"no_filter_{stage}_median_ms")
        if on is not None and off:
            out[f"full_filter_{key}_change_pct"] = 100.0 * (on - off) / off
    return out


@contextlib.contextmanager
def stage_cpu_clock():
    """The tracker times its stages with ``time.perf_counter``; inside this, with this thread's CPU time instead
    (the machine is shared: wall time would count the waits for a core)."""
    wall = time.perf_counter
    time.perf_counter = time.thread_time
    try:
        yield
    finally:
        time.perf_counter = wall


def filter_cost_runs(recording, contour_map, rounds: int, warm: int = 5) -> dict:
    """``full`` with and without the polarity filter on one recording, alternated ``rounds`` times (the order flips
    every round): :func:`change_table` of the pooled per-update stages, plus per state the ATE / ARE, the events
    kept and associated per update (means) and the share of events ``T_align`` removed."""
    from evpose.eval.metrics import Alignment, EvalConfig, evaluate
    from evpose.tracker.config import TrackerConfig, TrackerMode
    from evpose.tracker.session import TrackingSession

    stages: dict[str, dict[str, list[float]]] = {name: {} for name, _ in STATES}
    out: dict = {"rounds": rounds}
    for r in range(rounds):
        for name, enabled in (STATES if r % 2 == 0 else STATES[::-1]):
            cfg = TrackerConfig(mode=TrackerMode.FULL)
            cfg.polarity.enabled = enabled
            session = TrackingSession(recording, contour_map, cfg)
            with stage_cpu_clock():
                session.run()
            res = session.results
            for q in res[warm:]:
                for stage, v in stage_times(q.timings_ms).items():
                    stages[name].setdefault(stage, []).append(v)
            ev = evaluate(session.trajectory(), recording.ground_truth, EvalConfig(align=Alignment.NONE))
            out[f"{name}_ate_rmse_mm"], out[f"{name}_are_rmse_deg"] = float(ev.ate["rmse"] * 1e3), float(ev.are["rmse"])
            for key in ("events_kept", "events_registered"):
                out[f"{name}_{key}_per_update"] = float(np.mean([q.counts.get(key, 0) for q in res]))
            judged = sum(q.counts.get("events_polarity_judged", 0) for q in res)
            if judged:
                out[f"{name}_events_removed_share"] = sum(q.counts.get("events_polarity_removed", 0) for q in res) / judged
    out.update(change_table(stages))
    return out


def bench_full_filter_cost(ctx) -> dict:
    """``full`` with and without the polarity filter (see the module): the plain landing (240x180 1 s, one round with
    ``quick``; else 346x260 2 s, four rounds) and, in the full suite, the textured landing, whose ground carries
    texture the map lacks (the filter removes ~63 % of its events)."""
    import os

    from evpose.bench.tracking import landing_case

    res, seconds, rounds = ((240, 180), 1.0, 1) if ctx.quick else ((346, 260), 2.0, 4)
    out: dict = {"resolution": f"{res[0]}x{res[1]}", "seconds": seconds}
    scenarios = ("landing",) if ctx.quick else ("landing", "landing_texture")
    for scenario in scenarios:
        rec, cmap = landing_case(ctx.work_dir, res, seconds, ctx.seed, scenario=scenario)
        prefix = "" if scenario == "landing" else "texture_"
        out.update({f"{prefix}{k}": v for k, v in filter_cost_runs(rec, cmap, rounds).items()})
    la = os.getloadavg()
    out.update(load_avg_1min=float(la[0]), cpus=os.cpu_count() or 0)
    return out
