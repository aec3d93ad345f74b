"""The 3D scene: contour map, raw cloud, trajectories, the camera frustum with the live TDF, IMU-rate poses."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import viser
import viser.transforms as vtf

from app.frame import Frame, StepSummary
from app.panels import colormap
from evpose.core.camera import CameraCalibration
from evpose.core.contour_map import ContourMap
from evpose.core.trajectory import Trajectory

GREY = np.array([120, 120, 120], np.uint8)
VISIBLE = np.array([90, 200, 200], np.uint8)
ON = np.array([230, 40, 40], np.uint8)
OFF = np.array([40, 90, 230], np.uint8)
BUFFER = np.array([240, 200, 0], np.uint8)
MAX_CLOUD_POINTS = 40_000
"""The raw cloud is thinned to about this many points for display."""


@dataclass
class SceneToggles:
    """What the 3D view shows; each is a checkbox in the GUI."""

    contour_map: bool = True
    raw_cloud: bool = False
    ground_truth: bool = True
    registration: bool = True
    fused: bool = True
    imu_poses: bool = True
    frustum: bool = True
    follow: bool = False
    """Move every browser's camera with the tracked camera."""


def map_colours(n: int, frame: Frame | None) -> np.ndarray:
    """Per map point: grey not visible, cyan visible, red/blue predicted ON/OFF, yellow buffer zone."""
    cols = np.tile(GREY, (n, 1))
    if frame is None:
        return cols
    if frame.visible_index is not None and len(frame.visible_index):
        vi = frame.visible_index[(frame.visible_index >= 0) & (frame.visible_index < n)]
        cols[vi] = VISIBLE
    if frame.point_index is not None and frame.predicted_polarity is not None and len(frame.point_index):
        pi, pol = frame.point_index, frame.predicted_polarity
        ok = (pi >= 0) & (pi < n)
        pi, pol = pi[ok], pol[ok]
        cols[pi[pol > 0]] = ON
        cols[pi[pol < 0]] = OFF
        cols[pi[pol == 0]] = BUFFER
    return cols


def polyline_segments(positions: np.ndarray) -> np.ndarray:
    """(N, 3) positions -> (N-1, 2, 3) line segments."""
    p = np.asarray(positions, np.float32).reshape(-1, 3)
    if len(p) < 2:
        return np.zeros((0, 2, 3), np.float32)
    return np.stack([p[:-1], p[1:]], axis=1)


def _wxyz(T: np.ndarray) -> np.ndarray:
    return vtf.SO3.from_matrix(np.asarray(T)[:3, :3]).wxyz


class SceneView:
    """Owns the scene nodes; ``load`` sets the static content, ``update`` the per-step content."""

    def __init__(self, server: viser.ViserServer):
        self.server = server
        self.toggles = SceneToggles()
        self.contour_map: ContourMap | None = None
        self.calibration: CameraCalibration | None = None
        self.scale = 1.0
        self.ground_truth: Trajectory | None = None
        self._nodes: dict[str, object] = {}
        server.scene.set_up_direction("+z")
        server.scene.world_axes.visible = False

    def _set(self, name: str, handle) -> None:
        # Adding a node under an existing scene path replaces it in viser; only the newest handle is kept.
        self._nodes[name] = handle

    def clear(self) -> None:
        for h in self._nodes.values():
            h.remove()
        self._nodes.clear()

    def load(self, contour_map: ContourMap | None, cloud: tuple[np.ndarray, np.ndarray | None] | None,
             ground_truth: Trajectory | None, calibration: CameraCalibration | None) -> None:
        self.clear()
        self.contour_map, self.calibration = contour_map, calibration
        extent_pts = [a for a in (contour_map.points if contour_map is not None and len(contour_map) else None,
                                  ground_truth.position if ground_truth is not None and len(ground_truth) else None) if a is not None]
        if extent_pts:
            allp = np.concatenate(extent_pts)
            self.scale = float(max(np.ptp(allp, axis=0).max(), 0.1))
            if contour_map is not None and len(contour_map):
                # Frame the map (what is being tracked), not the whole flight.
                self.scale = float(max(np.ptp(contour_map.points, axis=0).max(), 0.1))
        pt = 0.006 * self.scale
        if contour_map is not None and len(contour_map):
            self._set("map", self.server.scene.add_point_cloud(
                "/map", contour_map.points.astype(np.float32), map_colours(len(contour_map), None),
                point_size=pt, point_shape="circle", visible=self.toggles.contour_map))
        if cloud is not None and len(cloud[0]):
            pts, cols = cloud
            # A fixed stride keeps the browser responsive on dense clouds (same points every time).
            stride = max(1, len(pts) // MAX_CLOUD_POINTS)
            pts = pts[::stride]
            cols = cols[::stride] if cols is not None else None
            cols = cols if cols is not None else np.array([170, 170, 170], np.uint8)
            self._set("cloud", self.server.scene.add_point_cloud(
                "/cloud", np.asarray(pts, np.float32), cols, point_size=pt * 0.7, visible=self.toggles.raw_cloud))
        if ground_truth is not None and len(ground_truth) > 1:
            self._set("gt", self.server.scene.add_line_segments(
                "/trajectory/ground_truth", polyline_segments(ground_truth.position), (40, 170, 60),
                thickness=2.0, thickness_units="screen", visible=self.toggles.ground_truth))
        focus = extent_pts[0] if extent_pts else np.zeros((1, 3))
        centre = focus.mean(axis=0)
        zmin = float(focus[:, 2].min())
        self._set("grid", self.server.scene.add_grid(
            "/grid", width=2 * self.scale, height=2 * self.scale, cell_size=self.scale / 10, section_size=self.scale / 2,
            position=(float(centre[0]), float(centre[1]), zmin)))
        self.ground_truth = ground_truth
        self._frame_view(centre, zmin)

    def _frame_view(self, centre: np.ndarray, zmin: float) -> None:
        """Point the initial (and every connected) browser camera obliquely at the scene."""
        look = np.array([centre[0], centre[1], zmin], float)
        eye = look + np.array([-1.2, -1.2, 1.4]) * self.scale
        cam = self.server.initial_camera
        cam.position, cam.look_at, cam.up = tuple(eye), tuple(look), (0.0, 0.0, 1.0)
        for client in self.server.get_clients().values():
            with client.atomic():
                client.camera.position = eye
                client.camera.look_at = look

    def apply_toggles(self) -> None:
        t = self.toggles
        for name, on in (("map", t.contour_map), ("cloud", t.raw_cloud), ("gt", t.ground_truth), ("reg", t.registration),
                         ("fused", t.fused), ("imu", t.imu_poses), ("frustum", t.frustum)):
            if name in self._nodes:
                self._nodes[name].visible = on

    def update(self, frame: Frame, history: list[StepSummary] | None) -> None:
        """Draw the per-step content of ``frame``; ``history`` (None = leave as drawn) gives the trajectories so far."""
        t = self.toggles
        scene = self.server.scene
        if "map" in self._nodes and self.contour_map is not None:
            self._nodes["map"].colors = map_colours(len(self.contour_map), frame)
        if history is not None:
            self._trajectories(history)
        if frame.slam is not None:
            self._slam(frame)
        self._camera(frame)

    def _slam(self, frame: Frame) -> None:
        """SLAM mode: the growing map of the active atlas map and its keyframes (in that map's own frame and scale)."""
        scene = self.server.scene
        v = frame.slam
        if v.map_points is not None and len(v.map_points):
            pts = np.asarray(v.map_points, np.float32)
            # Event-only maps have an arbitrary scale: size the points to the map itself.
            extent = float(max(np.ptp(pts, axis=0).max(), 1e-3))
            self._set("slam_map", scene.add_point_cloud("/slam/map_points", pts, np.tile(np.array([[20, 160, 220]], np.uint8), (len(pts), 1)),
                                                         point_size=0.008 * extent, point_shape="circle"))
            if v.keyframe_poses is not None and len(v.keyframe_poses):
                P = v.keyframe_poses
                self._set("slam_kf", scene.add_batched_axes(
                    "/slam/keyframes", batched_wxyzs=np.stack([_wxyz(T) for T in P]), batched_positions=P[:, :3, 3].astype(np.float32),
                    axes_length=0.04 * extent, axes_radius=0.003 * extent))
        elif "slam_map" in self._nodes and v.map_id < 0:
            for name in ("slam_map", "slam_kf"):
                if name in self._nodes:
                    self._nodes.pop(name).remove()

    def _trajectories(self, history: list[StepSummary]) -> None:
        t = self.toggles
        scene = self.server.scene
        fused = np.array([s.pose[:3, 3] for s in history if s.pose is not None]).reshape(-1, 3)
        reg = np.array([s.registration_pose[:3, 3] for s in history if s.registration_pose is not None]).reshape(-1, 3)
        if len(fused) > 1:
            self._set("fused", scene.add_line_segments("/trajectory/fused", polyline_segments(fused), (230, 120, 20),
                                                        thickness=3.0, thickness_units="screen", visible=t.fused))
        if len(reg) > 1:
            self._set("reg", scene.add_line_segments("/trajectory/registration", polyline_segments(reg), (150, 60, 200),
                                                      thickness=1.5, thickness_units="screen", visible=t.registration))

    def _camera(self, frame: Frame) -> None:
        t = self.toggles
        scene = self.server.scene
        if frame.imu_poses is not None and len(frame.imu_poses):
            P = frame.imu_poses
            self._set("imu", scene.add_batched_axes(
                "/imu_poses", batched_wxyzs=np.stack([_wxyz(T) for T in P]), batched_positions=P[:, :3, 3].astype(np.float32),
                axes_length=0.02 * self.scale, axes_radius=0.002 * self.scale, visible=t.imu_poses))
        pose = frame.pose if frame.pose is not None else frame.registration_pose
        if pose is None and self.ground_truth is not None and len(self.ground_truth):
            # Events-only view: show where the camera truly was, so the images have a place in 3D.
            pose = self.ground_truth.interpolate(frame.t_us).matrix(0)
        if pose is not None and self.calibration is not None:
            c = self.calibration
            fov = 2.0 * np.arctan2(c.height / 2.0, c.fy)
            img = colormap(1.0 - np.clip(frame.tdf, 0, 1), 2)  # COLORMAP_JET on edge strength
            if "frustum" not in self._nodes:
                self._set("frustum", scene.add_camera_frustum(
                    "/camera", fov=float(fov), aspect=c.width / c.height, scale=0.06 * self.scale, image=img,
                    format="jpeg", wxyz=_wxyz(pose), position=pose[:3, 3], color=(230, 120, 20), visible=t.frustum))
            else:
                h = self._nodes["frustum"]
                h.wxyz, h.position, h.image = _wxyz(pose), pose[:3, 3], img
            if t.follow:
                self.follow(pose)

    def follow(self, pose: np.ndarray) -> None:
        """Put each connected browser's camera behind and above the tracked camera, looking where it looks."""
        fwd = pose[:3, 2]
        # Behind and a little beside the camera, so the frustum and what it looks at are both in view.
        eye = pose[:3, 3] - fwd * 0.8 * self.scale + pose[:3, 0] * 0.3 * self.scale
        look = pose[:3, 3] + fwd * 0.8 * self.scale
        for client in self.server.get_clients().values():
            with client.atomic():
                client.camera.position = eye
                client.camera.look_at = look
