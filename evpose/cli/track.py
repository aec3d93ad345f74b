"""``evpose track RECORDING --map MAP --out EST.txt``: track the camera pose against a contour map (EV-Pose STPE)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import tyro

from evpose.cli.map_check import AcquisitionCheck, check_acquire_s
from evpose.errors import InputError
from evpose.tracker.map_acquisition import DEFAULT_ACQUIRE_S


def parse_init(text: str) -> np.ndarray | None:
    """'gt' -> None (first ground-truth pose); 'tx ty tz qx qy qz qw' -> 4x4 ``T_world_cam``."""
    if text.strip().lower() == "gt":
        return None
    from scipy.spatial.transform import Rotation

    try:
        vals = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        vals = []
    if len(vals) != 7 or not np.all(np.isfinite(vals)):
        raise InputError(None, f"--init expects 'gt' or seven numbers 'tx ty tz qx qy qz qw', got {text!r}")
    from evpose.core.trajectory import MAX_COORDINATE_M, quaternion_problem

    q = np.asarray(vals[3:])
    bad = quaternion_problem(q[None])  # a component of 1e300 overflowed the norm: scipy's "zero norm" traceback
    if bad is not None:
        raise InputError(None, f"--init {bad[1]}")
    if np.abs(vals[:3]).max() > MAX_COORDINATE_M:
        raise InputError(None, f"--init position {vals[:3]} is beyond {MAX_COORDINATE_M:g} m (not metres?)")
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(q / np.linalg.norm(q)).as_matrix()
    T[:3, 3] = vals[:3]
    return T


def timings_document(results, config) -> dict:
    """Per-update, per-module latencies plus their summaries (the ``--timings`` file)."""
    from evpose.bench.stats import latency_summary
    from evpose.tracker.config import config_to_dict

    modules = sorted({k for r in results for k in r.timings_ms})
    return {
        "config": config_to_dict(config),
        "modules": modules,
        "summary_ms": {m: latency_summary([r.timings_ms[m] for r in results if m in r.timings_ms]) for m in modules},
        "updates": [
            {"t_us": int(r.t_us), "status": r.status.value, "reason": r.reason, "timings_ms": r.timings_ms, "counts": r.counts}
            for r in results
        ],
    }


def smoothed_over_restarts(cfg, recording, inputs, restarts, lag_states: int = 400):
    """The smoothed trajectory of each stretch the fusion ran without a restart (``session.restarts``: after an event
    gap the backend starts again, and a replay across the gap would integrate the missing IMU), joined; each state
    re-estimated with the registrations of the next ``lag_states - 1`` updates."""
    from evpose.core.trajectory import Trajectory
    from evpose.fusion.replay import FusionInputs, smoothed_trajectory

    starts = [(inputs.t0_us, inputs.T0_world_cam, inputs.velocity0_world)] + [(t, T, v) for t, (T, v) in sorted(restarts.items())]
    parts = []
    for k, (t0, T0, v0) in enumerate(starts):
        t1 = starts[k + 1][0] if k + 1 < len(starts) else None
        reports = [r for r in inputs.reports if r[0] > t0 and (t1 is None or r[0] < t1)]
        if reports:
            parts.append(smoothed_trajectory(cfg.fusion, recording.calibration, recording.imu, FusionInputs(t0, T0, v0, reports),
                                             lag_states))
    if len(parts) == 1:
        return parts[0]
    if not parts:
        return Trajectory.empty()
    return Trajectory.from_arrays(np.concatenate([p.t for p in parts]), np.concatenate([p.position for p in parts]),
                                  np.concatenate([p.quat_xyzw for p in parts]))


def _check_smoothed(cfg) -> None:
    """--smoothed replays the factor graph: refused for another mode or backend before the recording and map are read
    (it came after them, 5 s into a 0.6 s recording; session 32)."""
    from evpose.fusion import FusionBackend
    from evpose.tracker.config import TrackerMode

    if cfg.mode is not TrackerMode.FULL or cfg.fusion.backend is not FusionBackend.FACTOR_GRAPH:
        raise InputError(None, f"--smoothed needs --mode full with the factor_graph fusion, not {cfg.mode.value} / {cfg.fusion.backend.value}")


def _record_fusion_inputs(session):
    """Have the session's factor graph log what it is fed, for the smoothed trajectory written after the run (the mode and
    backend were checked by :func:`_check_smoothed` before the inputs were read)."""
    from evpose.fusion.replay import FusionInputs

    motion = session.tracker.components.motion
    inputs = FusionInputs(int(motion.last.t_us), motion.last.T_world_cam.copy(), motion.initial_velocity_world)
    motion.input_log = inputs.reports
    return inputs


def main(
    recording: tyro.conf.Positional[Path],
    map: Path,  # noqa: A002 - the CLI flag is --map
    out: Path,
    mode: str | None = None,
    fusion: str | None = None,
    rate_hz: float | None = None,
    init: str = "gt",
    config: Path | None = None,
    timings: Path | None = None,
    smoothed: Path | None = None,
    smoothed_lag: int | None = None,
    width: int | None = None,
    height: int | None = None,
    progress: bool = True,
    acquire_s: float = DEFAULT_ACQUIRE_S,
) -> int:
    """Track the pose of the event camera of RECORDING against the contour map MAP; write a TUM trajectory.

    Args:
        recording: Anything ``evpose info`` reads (ECD folder, evpose .h5, event .h5, bag).
        map: Contour map from ``evpose build-map`` (.ply) or a plain point cloud (.ply/.pcd).
        out: TUM trajectory of ``T_world_cam``, one line per successful update.
        mode: stpe, stpe+filter or full (default from the config).
        fusion: Fusion backend of the fused modes: factor_graph (iSAM2 + fixed-lag window), ekf (error-state EKF
            baseline) or imu_only (dead reckoning from the initial state).
        rate_hz: Pose updates per second of recording time (default from the config: 200).
        init: 'gt' (first ground-truth pose) or 'tx ty tz qx qy qz qw' (pose at the first event). With a pose given, a
            restart after a long event gap starts from the last estimate; with ``reacquisition: {enabled: true}`` in
            --config it searches for the pose around it instead (pose hypotheses tracked side by side, the best
            accepted only if it clearly beats the others; see evpose.tracker.reacquisition), the updates of the
            search reported lost ("re-acquisition ...") until one is accepted.
        config: Tracker configuration, YAML or JSON (see ``evpose.tracker.config``).
        timings: Write per-update, per-module latencies (ms) and counts to this JSON file.
        smoothed: Also write the factor graph's smoothed trajectory here (``full`` mode, factor_graph backend only):
            each state re-estimated with the registrations of the next 2 s. An offline product, more accurate than
            OUT (which holds the estimates as they were available in real time).
        smoothed_lag: States (updates) each smoothed pose waits for (with --smoothed): 400 by default (2 s at 200 Hz),
            the most accurate offline trajectory; the fusion's own window (``fusion.window_states``, 8: 35 ms) gives the trajectory its
            sliding-window joint optimisation corrects, which a live system has that much later.
        width: Sensor width, for formats that do not state it.
        height: Sensor height, for formats that do not state it.
        progress: Show a progress bar on the terminal.
        acquire_s: If no update registers against the map within this many seconds of the start, stop with an error
            (a wrong map, or one in another frame; the fused modes would otherwise write IMU dead reckoning), and also
            if the registrations in those seconds are no better than chance (a wrong map where events cover the image
            densely: flicker, texture; see evpose.tracker.map_acquisition); 0 = never.

    Exit code 0 if every update tracked, 1 if the track was lost in some update
    (those updates are left out of the trajectory and reported on stderr).
    """
    from tqdm import tqdm

    from evpose.io.atomic import atomic_path, check_outputs, output_set
    from evpose.io.map_ply import read_contour_map
    from evpose.tracker.session import MapOutOfViewError
    from evpose.io.open import open_recording, require_calibration
    from evpose.io.tum import write_tum
    from evpose.tracker.config import TrackerConfig, TrackerMode, load_config
    from evpose.tracker.session import TrackingSession
    from evpose.tracker.step_result import TrackStatus

    check_outputs((out, timings, smoothed), inputs=(recording, map, config))
    if smoothed_lag is not None and smoothed is None:
        raise InputError(None, "--smoothed-lag needs --smoothed FILE (the trajectory it sets the lag of)")
    if smoothed_lag is not None and smoothed_lag < 2:
        raise InputError(None, f"--smoothed-lag must be at least 2 states, got {smoothed_lag}")
    cfg = load_config(config) if config is not None else TrackerConfig()
    if mode is not None:
        try:
            cfg.mode = TrackerMode(mode)
        except ValueError:
            raise InputError(None, f"--mode must be one of {', '.join(m.value for m in TrackerMode)}, got {mode!r}") from None
    if rate_hz is not None:
        if not rate_hz > 0:
            raise InputError(None, f"--rate-hz must be positive, got {rate_hz}")
        cfg.rate_hz = float(rate_hz)
    if fusion is not None:
        from evpose.fusion import FusionBackend

        aliases = {"imu-only": "imu_only", "factor-graph": "factor_graph"}
        try:
            cfg.fusion.backend = FusionBackend(aliases.get(fusion, fusion))
        except ValueError:
            raise InputError(None, f"--fusion must be one of {', '.join(b.value for b in FusionBackend)}, got {fusion!r}") from None
    from evpose.io.config_file import check_config

    check_config(cfg)  # --rate-hz inf would run a million updates per second of recording
    # The command writes poses only: the fused modes' marginal pose covariance (StepResult.covariance, which the fused
    # estimate never reads) would cost each update ~0.09 ms CPU for nothing (session 40, lt40: `full` 346x260 seed 0,
    # load ~8, median 87-91 us per update of ~2.7-4 ms; the trajectory is bit for bit the same).
    cfg.fusion.compute_covariance = False
    if smoothed is not None:
        _check_smoothed(cfg)
    check_acquire_s(acquire_s)
    initial = parse_init(init)
    cmap = read_contour_map(map)
    rec = open_recording(recording, width, height)
    require_calibration(rec, "tracking needs intrinsics")
    try:
        session = TrackingSession(rec, cmap, cfg, initial_pose=initial, seekable=False)  # memory: see ``seekable``
    except MapOutOfViewError as exc:
        raise InputError(map, f"{exc.problem} (recording {recording})") from None
    if session.total_steps == 0:
        # Otherwise this exits 0 saying "0 poses written" and writes no file at all.
        raise InputError(recording, f"no pose update to run: the events end at {session.t_end_us} us, less than one update"
                         f" ({session.dt_us} us) after the start at {session.t0_us} us"
                         + (" (the first ground-truth pose)" if initial is None else ""))
    inputs = _record_fusion_inputs(session) if smoothed is not None else None

    lost = []
    acquisition = AcquisitionCheck(session, acquire_s, map, recording.name)
    with tqdm(total=session.total_steps, unit="upd", disable=not progress or None, file=sys.stderr, dynamic_ncols=True) as bar:
        def tick(r):
            if r.status is TrackStatus.LOST:
                lost.append(r)
            acquisition.update(r)
            bar.update(1)

        session.run(progress=tick)
    traj = session.trajectory()
    # The outputs appear together (a Ctrl+C between two left a new --timings beside the last run's trajectory); with
    # no pose to write, an earlier run's OUT goes with the set it belonged to.
    with output_set(remove=() if len(traj) or not out.is_file() else (out,)):
        if timings is not None:
            doc = timings_document(session.results, cfg)
            with atomic_path(timings, inputs=(recording, map)) as tmp:
                tmp.write_text(json.dumps(doc, indent=1) + "\n")
        if len(traj):
            write_tum(out, traj, inputs=(recording, map))
        if inputs is not None:
            smooth = smoothed_over_restarts(cfg, rec, inputs, session.restarts, smoothed_lag or 400)
            # Not the updates reported lost either (those after a restart that ``restart_gate`` withheld: cut 0.2 s
            # splice of event_gaps, 353 smoothed poses metres off after the gap otherwise).
            smooth = smooth[~np.isin(smooth.t, np.array([r.t_us for r in lost], dtype=np.int64))] if lost and len(smooth) else smooth
            write_tum(smoothed, smooth, inputs=(recording, map))
    n = len(session.results)
    if lost:
        first = lost[0]
        print(
            f"evpose track: lost track in {len(lost)} of {n} updates (first at t={first.t_us * 1e-6:.6f} s: {first.reason});"
            f" {len(traj)} poses written to {out if len(traj) else 'nothing'}",
            file=sys.stderr,
        )
        return 1
    print(f"evpose track: {n} updates, {len(traj)} poses written to {out}", file=sys.stderr)
    return 0
