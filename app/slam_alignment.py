"""SLAM maps shown against the ground truth: each atlas map Sim(3)-aligned with evo's Umeyama, for display only.

Event-only maps live in a frame and scale of their own (and an inertial map in
a gravity-aligned frame of its own), so drawn as they are they overlap near the
origin at arbitrary sizes. When the recording has ground truth, each map is
aligned the way ``evpose eval --atlas --correct-scale`` scores it
(:func:`evpose.eval.slam_metrics.map_metrics`): its estimates inside the ground
truth's span, the ground truth interpolated at their times, and evo's Umeyama
alignment of the positions, with scale for event-only maps and without for
maps the IMU initialisation made metric. The alignment uses the ground truth,
which the SLAM never sees: it is a way to look at the maps, not part of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.eval.sim3_alignment import Sim3, align_to_ground_truth


@dataclass
class AtlasMapView:
    """One map of the atlas as the 3D view draws it (in the map's own frame) and its alignment."""

    map_id: int
    active: bool
    points: np.ndarray
    """Map points (M, 3), map units."""
    keyframe_poses: np.ndarray
    """``T_world_cam`` of the keyframes (K, 4, 4), map units."""
    trajectory: np.ndarray
    """Camera positions of the map's per-MCI poses, refined by its bundle adjustments (N, 3), map units."""
    alignment: Sim3 | None
    """Map -> ground truth (None: no ground truth, or too few or degenerate poses)."""
    scaled: bool
    """The alignment has a scale (event-only map) rather than being rigid (metric, IMU-initialised map)."""


class AtlasAligner:
    """Views of every map of an atlas with their alignments; a map no longer active does not change, so it is
    computed once (per map id and size)."""

    def __init__(self, ground_truth: Trajectory | None):
        self.ground_truth = ground_truth
        self._done: dict[tuple, AtlasMapView] = {}

    def _view(self, m, active: bool) -> AtlasMapView:
        # The active map is drawn anew at every step: its PnP poses are re-solved on the final points only once it
        # is done (evpose.slam.pose_refit costs up to tens of milliseconds on a grown map).
        traj = m.trajectory(refined=True, refit=not active)
        kfs = np.stack([k.T_wc for k in m.keyframes]) if m.keyframes else np.zeros((0, 4, 4))
        scaled = not m.imu_initialised
        return AtlasMapView(m.id, active, m.point_array(), kfs, traj.position.copy() if len(traj) else np.zeros((0, 3)),
                            align_to_ground_truth(traj, self.ground_truth, correct_scale=scaled), scaled)

    def views(self, atlas) -> list[AtlasMapView]:
        """One view per map of ``atlas`` (``evpose.slam.atlas.Atlas``) with at least one point or pose."""
        out = []
        for i, m in enumerate(atlas.maps):
            if not m.points and not m.traj_t:
                continue
            active = i == len(atlas.maps) - 1
            if active:
                out.append(self._view(m, True))
                continue
            key = (m.id, len(m.traj_t), len(m.keyframes), len(m.points))
            if key not in self._done:
                self._done[key] = self._view(m, False)
            out.append(self._done[key])
        return out


def alignment_note(views: list[AtlasMapView], aligned: bool, has_ground_truth: bool) -> str:
    """Plain words on how the 3D view places the maps, naming the ground truth when it is used."""
    if not views:
        return ""
    if not has_ground_truth:
        return "3D view: no ground truth in this recording, so each map is drawn in its own frame and scale."
    if not aligned:
        return ("3D view: raw, each map in its own frame and scale (event-only maps have an arbitrary scale); "
                "tick *slam aligned* to place them on the ground truth.")
    parts = [f"map {v.map_id}: " + (f"Sim(3), scale {v.alignment.s:.3g} m/unit" if v.scaled else "SE(3), metric")
             if v.alignment is not None else f"map {v.map_id}: too few poses to align, drawn raw" for v in views]
    return ("3D view: each map aligned to the **ground truth** (evo's Umeyama on its poses, as `evpose eval --atlas "
            "--correct-scale`): " + "; ".join(parts) + ". The alignment uses the ground truth, which SLAM never sees; "
            "untick *slam aligned* for the maps' own frames.")
