"""The 3D scene: contour map, raw cloud, trajectories, the camera frustum with the live TDF, IMU-rate poses."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import viser
import viser.transforms as vtf
from scipy.spatial import cKDTree

from app.frame import Frame, StepSummary
from app.frame_cache import quantize
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
FRUSTUM_IMAGE_WIDTH = 176
"""The TDF shown inside the camera frustum is shrunk to at most this width (it is drawn small), pixels."""
SLAM_ACTIVE = np.array([20, 160, 220], np.uint8)
SLAM_OLD = np.array([150, 150, 190], np.uint8)
"""Points of the active SLAM map, and of the maps tracking lost earlier."""
POINT_PRECISION = "float32"
"""Point positions as sent to the browser. viser's default float16 keeps ~3 digits (8 mm steps at 10 m, 6 cm at
100 m) and overflows past 65504: SLAM maps with far outliers logged "overflow encountered in cast" and drew them
at infinity."""
SLAM_POINT_SPACING = 0.4
"""A SLAM map point is drawn this fraction of the map's median nearest-neighbour spacing wide, so neighbours never
merge. viser sizes points in world units only: at 0.008 x the flight's extent (6.5 cm on the landing demo, whose
SLAM map points are 7.5 cm apart) they overlapped into blobs ~25 px wide in the teaching layout's follow view."""
SLAM_POINT_RANGE = (0.002, 0.008)
"""Bounds on a SLAM map point's width, as fractions of the scene's extent (visible in the overview, never huge)."""
TRAJECTORY_CHUNK = 256
"""Trajectory polylines are sent in chunks of this many steps; only the newest chunk changes as the run grows."""


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
    slam_aligned: bool = True
    """SLAM mode: draw each atlas map Sim(3)-aligned to the ground truth (when the recording has one), else in its own frame."""


def map_colours(n: int, frame: Frame | None, base: np.ndarray | None = None) -> np.ndarray:
    """Per map point: grey not visible, cyan visible, red/blue predicted ON/OFF, yellow buffer zone.

    ``base`` (an (n, 3) all-grey array) is copied instead of building one, which is most of the cost on big maps.
    """
    cols = base.copy() if base is not None and len(base) == n else np.tile(GREY, (n, 1))
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


def frustum_image(tdf: np.ndarray) -> np.ndarray:
    """The TDF as edge strength (JET colour map), shrunk to at most ``FRUSTUM_IMAGE_WIDTH`` pixels wide."""
    img = colormap(255 - quantize(tdf), 2)  # COLORMAP_JET on 1 - TDF
    h, w = img.shape[:2]
    if w > FRUSTUM_IMAGE_WIDTH:
        f = FRUSTUM_IMAGE_WIDTH / w
        img = cv2.resize(img, (FRUSTUM_IMAGE_WIDTH, max(1, int(round(h * f)))), interpolation=cv2.INTER_AREA)
    return img


def trajectory_chunks(positions: np.ndarray, chunk: int = TRAJECTORY_CHUNK) -> list[np.ndarray]:
    """(N, 3) positions -> polyline segments in chunks of ``chunk`` steps; each chunk ends where the next starts."""
    p = np.asarray(positions, np.float32).reshape(-1, 3)
    return [polyline_segments(p[i : i + chunk + 1]) for i in range(0, max(len(p) - 1, 0), chunk)]


def slam_point_size(pts: np.ndarray, extent: float) -> float:
    """World width of a SLAM map's points: :data:`SLAM_POINT_SPACING` x their median spacing, bounded by
    :data:`SLAM_POINT_RANGE` x ``extent``."""
    lo, hi = SLAM_POINT_RANGE[0] * extent, SLAM_POINT_RANGE[1] * extent
    pts = np.asarray(pts, np.float64).reshape(-1, 3)
    if len(pts) < 2:
        return hi
    # A fixed stride bounds the cost on big maps (the active map is redrawn every step); same points every time.
    dist, _ = cKDTree(pts).query(pts[:: max(1, len(pts) // 2000)], k=2)
    return float(np.clip(SLAM_POINT_SPACING * np.median(dist[:, 1]), lo, hi))


def keyframe_axes_length(positions: np.ndarray, extent: float) -> float:
    """World length of a SLAM map's keyframe axes: 0.6 x the median step between consecutive keyframes, within
    0.01-0.04 x ``extent`` (at 0.04 x the flight's extent, 32 cm on the landing demo, keyframes a few cm apart drew
    one solid ladder of overlapping axes)."""
    lo, hi = 0.01 * extent, 0.04 * extent
    steps = np.linalg.norm(np.diff(np.asarray(positions, np.float64).reshape(-1, 3), axis=0), axis=1)
    return float(np.clip(0.6 * np.median(steps), lo, hi)) if len(steps) else hi


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
        self._grey: np.ndarray | None = None
        self._drawn_chunks: dict[str, list[tuple[int, object]]] = {}
        """Per trajectory: for each chunk sent, (points in it, the summary of its last point) to tell whether it changed."""
        self._slam_drawn: dict[int, object] = {}
        """SLAM map id -> the view (and whether aligned) last drawn for it: maps no longer active are not resent."""
        self._overview: tuple[np.ndarray, float] | None = None
        """The overview's look-at centre and ground height, from the last :meth:`load`."""
        self._followed = self.toggles.follow
        server.scene.set_up_direction("+z")
        server.scene.world_axes.visible = False

    def _set(self, name: str, handle) -> None:
        # Adding a node under an existing scene path replaces it in viser; only the newest handle is kept.
        self._nodes[name] = handle

    def clear(self) -> None:
        for h in self._nodes.values():
            h.remove()
        self._nodes.clear()
        self._drawn_chunks.clear()
        self._slam_drawn.clear()

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
        self._grey = np.tile(GREY, (len(contour_map), 1)) if contour_map is not None else None
        if contour_map is not None and len(contour_map):
            self._set("map", self.server.scene.add_point_cloud(
                "/map", contour_map.points.astype(np.float32), map_colours(len(contour_map), None),
                point_size=pt, point_shape="circle", visible=self.toggles.contour_map, precision=POINT_PRECISION))
        self.set_cloud(cloud)
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
        self._overview = (centre, zmin)
        self._frame_view(centre, zmin)

    def set_cloud(self, cloud: tuple[np.ndarray, np.ndarray | None] | None) -> None:
        """Draw (or replace) the raw cloud, at the scale of the last :meth:`load`."""
        if cloud is None or not len(cloud[0]):
            return
        pts, cols = cloud
        # A fixed stride keeps the browser responsive on dense clouds (same points every time).
        stride = max(1, len(pts) // MAX_CLOUD_POINTS)
        pts = pts[::stride]
        cols = cols[::stride] if cols is not None else None
        cols = cols if cols is not None else np.array([170, 170, 170], np.uint8)
        self._set("cloud", self.server.scene.add_point_cloud(
            "/cloud", np.asarray(pts, np.float32), cols, point_size=0.006 * self.scale * 0.7, visible=self.toggles.raw_cloud,
            precision=POINT_PRECISION))

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
        shown = {"map": t.contour_map, "cloud": t.raw_cloud, "gt": t.ground_truth, "reg": t.registration,
                 "fused": t.fused, "imu": t.imu_poses, "frustum": t.frustum}
        # A copy, and removed nodes skipped: the player thread may replace nodes meanwhile (a toggle or a layout
        # applied while it draws; it draws the new ones with these toggles already). Seen in session 28's suite: a
        # layout's nine checkboxes set while a redraw replaced the IMU-rate axes ("Cannot assign to 'visible' on a
        # removed BatchedAxesHandle").
        for name, node in list(self._nodes.items()):
            on = shown.get(name.split("/")[0])  # trajectory chunks are "fused/0", "fused/1", ...
            if on is not None:
                try:
                    node.visible = on
                except RuntimeError:
                    pass  # removed by the player thread since the copy
        if self._followed and not t.follow and self._overview is not None:
            # Leaving follow (its checkbox or a layout without it) left the camera a few metres behind the last
            # pose, close to the map: the debug/compare layouts then opened on a zoomed-in corner of the scene.
            self._frame_view(*self._overview)
        self._followed = t.follow

    def update(self, frame: Frame, history: list[StepSummary] | None) -> None:
        """Draw the per-step content of ``frame``; ``history`` (None = leave as drawn) gives the trajectories so far."""
        t = self.toggles
        scene = self.server.scene
        if "map" in self._nodes and self.contour_map is not None:
            self._nodes["map"].colors = map_colours(len(self.contour_map), frame, self._grey)
        if frame.slam is not None:
            # Per-step SLAM poses hop between the maps' frames: each map's own trajectory is drawn instead.
            self._slam(frame)
            if history is not None:
                self._trajectories([])
        elif history is not None:
            self._trajectories(history)
        self._camera(frame)

    def _slam(self, frame: Frame) -> None:
        """SLAM mode: every map of the atlas (points, keyframes, trajectory), aligned to the ground truth when the
        toggle is on and an alignment exists, else in the map's own frame and scale."""
        v = frame.slam
        views = v.atlas
        drawn = set()
        for view in views:
            sim = view.alignment if self.toggles.slam_aligned else None
            drawn.add(view.map_id)
            last = self._slam_drawn.get(view.map_id)
            if not view.active and last is not None and last[0] is view and last[1] == (sim is not None):
                continue  # a map no longer active (the aligner's same view) looks as when it was last sent
            self._slam_map(view, sim)
            self._slam_drawn[view.map_id] = (view, sim is not None)
        for map_id in [k for k in self._slam_drawn if k not in drawn]:  # maps not made yet after a seek back
            for part in ("slam_map", "slam_kf", "slam_traj"):
                node = self._nodes.pop(f"{part}/{map_id}", None)
                if node is not None:
                    node.remove()
            del self._slam_drawn[map_id]

    def _slam_map(self, view, sim) -> None:
        scene = self.server.scene
        pts = sim.points(view.points) if sim is not None else np.asarray(view.points, np.float64)
        kfs = sim.poses(view.keyframe_poses) if sim is not None else view.keyframe_poses
        traj = sim.points(view.trajectory) if sim is not None else view.trajectory
        # Aligned maps share the ground truth's scale; raw event-only maps have their own, so they size themselves.
        own = np.concatenate([pts.reshape(-1, 3), traj.reshape(-1, 3)])
        extent = self.scale if sim is not None else float(max(np.ptp(own, axis=0).max(), 1e-3)) if len(own) else 1.0
        colour = SLAM_ACTIVE if view.active else SLAM_OLD
        i = view.map_id
        if len(pts):
            self._set(f"slam_map/{i}", scene.add_point_cloud(f"/slam/map_{i}/points", pts.astype(np.float32), np.tile(colour, (len(pts), 1)),
                                                              point_size=slam_point_size(pts, extent), point_shape="circle", precision=POINT_PRECISION))
        if len(kfs):
            self._set(f"slam_kf/{i}", scene.add_batched_axes(
                f"/slam/map_{i}/keyframes", batched_wxyzs=np.stack([_wxyz(T) for T in kfs]), batched_positions=kfs[:, :3, 3].astype(np.float32),
                axes_length=(ax := keyframe_axes_length(kfs[:, :3, 3], extent)), axes_radius=0.075 * ax))
        if len(traj) > 1:
            self._set(f"slam_traj/{i}", scene.add_line_segments(
                f"/slam/map_{i}/trajectory", polyline_segments(traj), (230, 120, 20) if view.active else (200, 160, 110),
                thickness=2.5 if view.active else 1.5, thickness_units="screen"))

    def slam_pose(self, frame: Frame) -> np.ndarray | None:
        """The frame's camera pose where the 3D view draws the active map (aligned or raw)."""
        pose = frame.pose
        if pose is None or frame.slam is None or not self.toggles.slam_aligned:
            return pose
        active = next((m for m in frame.slam.atlas if m.active and m.map_id == frame.slam.map_id), None)
        return active.alignment.poses(pose) if active is not None and active.alignment is not None else pose

    def _trajectories(self, history: list[StepSummary]) -> None:
        t = self.toggles
        for key, attr, colour, width, visible in (("fused", "pose", (230, 120, 20), 3.0, t.fused),
                                                   ("reg", "registration_pose", (150, 60, 200), 1.5, t.registration)):
            steps = [s for s in history if getattr(s, attr) is not None]
            self._polyline(key, steps, attr, colour, width, visible)

    def _polyline(self, key: str, steps: list[StepSummary], attr: str, colour, width: float, visible: bool) -> None:
        """Send the polyline through ``steps`` in bounded chunks: unchanged chunks are not resent, extra ones removed."""
        drawn = self._drawn_chunks.setdefault(key, [])
        n_chunks = (len(steps) - 1 + TRAJECTORY_CHUNK - 1) // TRAJECTORY_CHUNK if len(steps) > 1 else 0
        for i in range(n_chunks):
            part = steps[i * TRAJECTORY_CHUNK : (i + 1) * TRAJECTORY_CHUNK + 1]
            sig = (len(part), part[-1])
            if i < len(drawn) and drawn[i][0] == sig[0] and drawn[i][1] is sig[1]:
                continue  # the same summaries as last time: the same segments
            pos = np.array([getattr(s, attr)[:3, 3] for s in part], np.float32)
            self._set(f"{key}/{i}", self.server.scene.add_line_segments(
                f"/trajectory/{key}/{i}", polyline_segments(pos), colour, thickness=width, thickness_units="screen", visible=visible))
            if i < len(drawn):
                drawn[i] = sig
            else:
                drawn.append(sig)
        for i in range(n_chunks, len(drawn)):
            node = self._nodes.pop(f"{key}/{i}", None)
            if node is not None:
                node.remove()
        del drawn[n_chunks:]

    def _camera(self, frame: Frame) -> None:
        t = self.toggles
        scene = self.server.scene
        if frame.imu_poses is not None and len(frame.imu_poses):
            P = frame.imu_poses
            self._set("imu", scene.add_batched_axes(
                "/imu_poses", batched_wxyzs=np.stack([_wxyz(T) for T in P]), batched_positions=P[:, :3, 3].astype(np.float32),
                axes_length=0.02 * self.scale, axes_radius=0.002 * self.scale, visible=t.imu_poses))
        pose = self.slam_pose(frame) if frame.slam is not None else frame.pose if frame.pose is not None else frame.registration_pose
        if pose is None and self.ground_truth is not None and len(self.ground_truth):
            # Events-only view: show where the camera truly was, so the images have a place in 3D.
            pose = self.ground_truth.interpolate(frame.t_us).matrix(0)
        if pose is not None and self.calibration is not None:
            c = self.calibration
            fov = 2.0 * np.arctan2(c.height / 2.0, c.fy)
            img = frustum_image(frame.tdf)
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
