"""``evpose info PATH``: describe a recording, a contour map (.ply/.pcd) or a TUM trajectory."""

from __future__ import annotations

import json
from pathlib import Path

import tyro

from evpose.errors import InputError


def _fmt_rate(hz: float) -> str:
    if hz >= 1e6:
        return f"{hz / 1e6:.2f} M"
    if hz >= 1e3:
        return f"{hz / 1e3:.1f} k"
    return f"{hz:.1f} "


def _recording_lines(s: dict) -> list[str]:
    size = s["sensor_size"]
    size_text = f"{size[0]} x {size[1]}" if size else "unknown (not stated by the file; pass --width/--height)"
    imu_text = f"{s['imu_samples']} samples at {s['imu_rate_hz']:.1f} Hz" if s["imu_samples"] else "none"
    gt_text = f"{s['ground_truth_poses']} poses" if s["ground_truth_poses"] else "none"
    lines = [
        f"source        {s['source']}",
        f"format        {s['format']}",
        f"sensor size   {size_text}",
        f"duration      {s['duration_s']:.6f} s  ({s['t_start_us']} .. {s['t_end_us']} us)",
        f"events        {s['events']}  ({_fmt_rate(s['event_rate_hz'])}ev/s, {100 * s['positive_share']:.1f} % ON)",
        *_gap_lines(s),
        f"imu           {imu_text}",
        f"ground truth  {gt_text}",
    ]
    cal = s["calibration"]
    if cal is None:
        note = " (calib.txt has intrinsics but no sensor size; pass --width/--height)" if "ecd_calib_txt" in s.get("metadata", {}) else ""
        lines.append(f"calibration   none{note}")
    else:
        lines.append(f"calibration   {cal['model']}  fx={cal['fx']:.3f} fy={cal['fy']:.3f} cx={cal['cx']:.3f} cy={cal['cy']:.3f}  dist={cal['dist']}")
        lines.append(f"              time offset {cal['time_offset_us']} us, T_cam_imu translation {[round(r[3], 6) for r in cal['T_cam_imu'][:3]]} m")
    return lines


def _gap_lines(s: dict) -> list[str]:
    from evpose.tracker.event_gaps import DEFAULT_MAX_EVENT_GAP_MS

    if s.get("longest_event_gap_s", 0.0) * 1e3 <= DEFAULT_MAX_EVENT_GAP_MS:
        return []
    return [f"event gap     {s['longest_event_gap_s']:.6f} s without events after t={s['longest_event_gap_after_us'] * 1e-6:.6f} s"
            f" (the longest; evpose track restarts after gaps over {DEFAULT_MAX_EVENT_GAP_MS / 1e3:g} s)"]


def describe(path: Path, width: int | None = None, height: int | None = None) -> dict:
    """The summary dict of whatever ``path`` is."""
    from evpose.io import summary

    suffix = path.suffix.lower()
    if path.name == "events.txt":  # the events file of an ECD folder: describe the folder
        path, suffix = path.parent, ""
    if suffix in (".ply", ".pcd"):
        return summary.summarize_map(path)
    if path.is_file() and suffix in (".txt", ".tum", ".csv"):
        from evpose.io.tum import is_tum_file, read_tum

        if not is_tum_file(path):
            raise InputError(path, "not a TUM trajectory (expected lines 't tx ty tz qx qy qz qw')")
        return summary.summarize_trajectory(read_tum(path), path)
    return summary.summarize_recording(path, width, height)


def main(
    path: tyro.conf.Positional[Path],
    width: int | None = None,
    height: int | None = None,
    json_output: bool = False,
) -> int:
    """Describe a recording (sensor size, duration, events and rate, IMU rate, ground truth, calibration), a contour map or a TUM trajectory.

    Args:
        path: ECD folder, evpose .h5, event .h5/.hdf5, ROS1 .bag, ROS2 bag, .ply/.pcd map or TUM .txt.
        width: Sensor width in pixels, for formats that do not state it (ECD text, event h5).
        height: Sensor height in pixels, for formats that do not state it.
        json_output: Print one JSON object instead of the table.
    """
    s = describe(path, width, height)
    if json_output:
        print(json.dumps(s, sort_keys=True))
        return 0
    if s["format"] == "map":
        print(f"source        {s['source']}\nformat        contour map\npoints        {s['points']}")
        print(f"bounds        min {[round(v, 4) for v in s['bounds_min_m']]} m, max {[round(v, 4) for v in s['bounds_max_m']]} m")
        print(f"regions       {s['regions']}")
        print(f"edge normals  {'yes' if s['edge_normals'] else 'no'}; plane normals {'yes' if s['plane_normals'] else 'no'}")
        print(f"brightness    {'known for ' + format(100 * s['brightness_signs_known_share'], '.1f') + ' % of points' if s['brightness_signs'] else 'unknown'}")
    elif s["format"] == "tum":
        print(f"source        {s['source']}\nformat        TUM trajectory\nposes         {s['poses']} ({s['rate_hz']:.1f} Hz)")
        print(f"duration      {s['duration_s']:.6f} s\npath length   {s['path_length_m']:.4f} m")
    else:
        print("\n".join(_recording_lines(s)))
    return 0
