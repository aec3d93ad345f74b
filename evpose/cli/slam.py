"""``evpose slam RECORDING --out EST.txt``: map-free event(-inertial) SLAM, one TUM trajectory per map of the atlas."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import tyro

from evpose.errors import InputError


def output_paths(out: Path, n_maps: int) -> list[Path]:
    """``EST.map0.txt``, ``EST.map1.txt``... next to ``out``."""
    return [out.with_name(f"{out.stem}.map{k}{out.suffix or '.txt'}") for k in range(n_maps)]


def stale_outputs(out: Path, n_maps: int, inputs=()) -> list[Path]:
    """An earlier run's outputs that a run with ``n_maps`` maps does not replace: its ``EST.map<k>`` files from
    ``k = n_maps`` on (``evpose eval --atlas`` would read them as this run's maps) and, with no map, ``out`` itself;
    never one of ``inputs``."""
    import os

    stale = [] if n_maps or not out.is_file() else [out]
    k = n_maps
    while (p := output_paths(out, k + 1)[k]).is_file():
        stale.append(p)
        k += 1
    return [p for p in stale if not any(Path(i).exists() and os.path.samefile(p, i) for i in inputs)]


def main(
    recording: tyro.conf.Positional[Path],
    out: Path,
    mode: str = "event",
    configuration: str | None = None,
    config: Path | None = None,
    summary: Path | None = None,
    width: int | None = None,
    height: int | None = None,
) -> int:
    """Run SLAM without a prior map on RECORDING and write TUM trajectories (``T_world_cam`` per MCI).

    OUT receives the longest map's trajectory; every map k of the atlas is also
    written to OUT with ``.map<k>`` before the suffix. Event-only maps have an
    arbitrary scale (evaluate with ``--align sim3``). A JSON summary (statuses,
    per-map sizes, per-MCI latencies and, with ground truth, the paper's metrics)
    goes to SUMMARY (default: OUT with suffix ``.slam.json``). The files appear
    together at the end, replacing an earlier run's set (its surplus ``.map<k>``
    files, and OUT when no map was made, are removed), or, if interrupted, not at all.

    Args:
        recording: Anything ``evpose info`` reads (ECD folder, evpose .h5, event .h5, bag); needs a calibration.
        out: TUM trajectory of the longest map.
        mode: event or event-inertial.
        configuration: Event-inertial configuration of the paper: c1 (a new map when lost), c2 (continuous: IMU bridges, the default) or c3 (c2 with a fixed tiny-window size); overrides the config file.
        config: SLAM configuration, YAML or JSON (see ``evpose.slam.config``).
        summary: Where to write the JSON summary.
        width: Sensor width, for formats that do not state it.
        height: Sensor height, for formats that do not state it.
    """
    from collections import Counter

    from evpose.bench.stats import latency_summary
    from evpose.eval.slam_metrics import atlas_metrics
    from evpose.io.atomic import atomic_path, check_outputs, output_set
    from evpose.io.open import open_recording, require_calibration
    from evpose.io.tum import write_tum
    from evpose.slam.config import SlamConfig, SlamMode
    from evpose.slam.config_io import config_to_dict, load_slam_config
    from evpose.slam.inertial import InertialConfiguration
    from evpose.slam.run import run_slam
    from evpose.slam.step_result import SlamFailure

    # Every output, the per-map files included, before the run: a refused --out used to leave EST.map<k> files behind.
    check_outputs((out, summary or out.with_suffix(".slam.json"), *output_paths(out, 1)), inputs=(recording, config))
    try:
        slam_mode = SlamMode(mode)
    except ValueError:
        raise InputError(None, f"--mode must be one of {[m.value for m in SlamMode]}, got {mode!r}") from None
    cfg = load_slam_config(config) if config is not None else SlamConfig()
    cfg.mode = slam_mode
    if configuration is not None:
        try:
            cfg.inertial.configuration = InertialConfiguration(configuration.lower())
        except ValueError:
            raise InputError(None, f"--configuration must be one of {[c.value for c in InertialConfiguration]}, got {configuration!r}") from None
    import cv2

    # One OpenCV thread: no oversubscription of small machines, and the per-stage CPU timings
    # in the summary then cover all the work.
    cv2.setNumThreads(1)
    rec = open_recording(recording, width, height)
    require_calibration(rec, "SLAM needs one")
    rec.validate()
    if len(rec.events) == 0:
        raise InputError(recording, "the recording has no events")
    run = run_slam(rec, cfg)
    inputs = tuple(p for p in (recording, config) if p is not None)
    maps = [m for m in run.atlas.maps if m.traj_t]
    trajs = [m.trajectory() for m in maps]
    doc = {
        "recording": str(recording),
        "config": config_to_dict(cfg),
        "mcis": sum(1 for r in run.results if r.failure is not SlamFailure.GAP),
        "status_counts": dict(sorted(Counter(r.status.value for r in run.results).items())),
        # Seconds under each status: a map's tracked time also holds its coasted poses; "ok" is what the events tracked.
        "time_by_status_s": run.time_by_status_s(),
        "visual_fraction": run.visual_fraction,
        # The time not tracked from the events, by why (blank view, too few tracked map points, pose rejected, no map).
        "time_by_failure_s": run.time_by_failure_s(),
        "hypothesis_counts": dict(sorted(Counter(r.hypothesis for r in run.results if r.hypothesis).items())),
        "maps": [{"id": m.id, "poses": len(m.traj_t), "keyframes": len(m.keyframes), "points": len(m.points), "lost_reason": m.lost_reason,
                  "imu_initialised": m.imu_initialised, "imu_scale": m.scale} for m in maps],
        "latency_ms": {k: latency_summary([r.timings_ms[k] for r in run.results if k in r.timings_ms]) for k in ("mci", "tracking", "total", "mci_cpu", "tracking_cpu")},
        "wall_s": run.wall_s,
        "duration_s": run.duration_s,
    }
    if rec.ground_truth is not None and len(rec.ground_truth) >= 2 and trajs:
        doc["metrics"] = atlas_metrics(trajs, rec.ground_truth, correct_scale=slam_mode is SlamMode.EVENT, duration_s=run.duration_s).to_dict()
    summary = summary or out.with_suffix(".slam.json")
    # One set: an interrupt between two files left maps without their summary (or beside the last run's).
    with output_set(remove=stale_outputs(out, len(trajs), inputs)):
        for path, traj in zip(output_paths(out, len(trajs)), trajs):
            write_tum(path, traj, inputs=inputs)
        if trajs:
            write_tum(out, max(trajs, key=len), inputs=inputs)
        with atomic_path(summary, inputs=inputs) as tmp:
            tmp.write_text(json.dumps(doc, indent=2, default=float) + "\n")
    if not trajs:
        reasons = Counter(r.reason for r in run.results if r.reason)
        why = reasons.most_common(1)[0][0] if reasons else "no motion-compensated image was produced (too few events, no texture or a still camera)"
        print(f"evpose slam: not initialised: {why}", file=sys.stderr)
        return 1
    print(f"evpose slam: {len(trajs)} map(s), {sum(len(t) for t in trajs)} poses -> {out}", file=sys.stderr)
    return 0
