"""Smooth rig trajectories: C2 position splines and analytic orientations.

Position is a cubic spline (``scipy.interpolate.CubicSpline``, twice
continuously differentiable) through waypoints timed by arc length, so the
IMU's specific force is the spline's exact second derivative. Orientation is
an analytic function of time (yaw ramp + sinusoidal tilts); body rates come
from a central difference of ``R_wb`` over +-``_DT_RATE`` seconds, whose error
(~dt^2 * omega''' / 6) is below 1e-9 rad/s here.

The trajectory describes the IMU body frame B; the camera pose follows from
``T_world_cam = T_world_body @ inv(T_cam_imu)``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from evpose.core.trajectory import Trajectory, invert_pose

_DT_RATE = 1e-4  # s, half-width of the central difference for body rates
_R_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])  # camera looking straight down
_R_FORWARD = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # camera looking along +x, level


class TrajectoryShape(str, enum.Enum):
    SPIRAL_LANDING = "spiral_landing"
    """EV-Pose field study: a square spiral descending onto the pad at (0, 0), camera looking down."""
    ROOM_LOOP = "room_loop"
    """An ellipse around the room centre, camera looking outward at the walls."""


@dataclass(frozen=True)
class TrajectoryConfig:
    """Shape and speed of the simulated flight."""

    shape: TrajectoryShape = TrajectoryShape.SPIRAL_LANDING
    """Which path to fly."""
    speed_m_s: float = field(default=3.0, metadata={"min": 0.1, "max": 10.0, "unit": "m/s"})
    """Nominal speed along the path, m/s (EV-Pose: slow < 2, moderate 2-4, fast > 4)."""
    leg_length_m: float = 5.0
    """Target length of one straight leg of the square spiral, metres."""
    start_altitude_m: float = 9.0
    """Highest altitude of the spiral (reached only when the path is long enough), metres."""
    end_altitude_m: float = 3.0
    """Altitude above ground at the end, over the pad, metres."""
    descent_ratio: float = 0.4
    """Altitude lost per metre of path (capped by the start altitude)."""
    yaw_rate_deg_s: float = field(default=0.0, metadata={"min": -360.0, "max": 360.0, "unit": "deg/s"})
    """Constant yaw rate added on top of the oscillation, deg/s."""
    yaw_amplitude_deg: float = 8.0
    """Amplitude of a slow yaw oscillation, degrees."""
    tilt_amplitude_deg: float = 4.0
    """Amplitude of the roll/pitch oscillations, degrees."""
    oscillation_hz: float = 0.6
    """Frequency of the yaw/tilt oscillations, Hz."""
    bob_amplitude_m: float = 0.1
    """Vertical bobbing amplitude, metres (keeps the accelerometer busy on straight legs)."""
    room_radii_m: tuple[float, float] = (1.6, 0.9)
    """Ellipse radii of the room loop, metres."""
    room_height_m: float = 1.4
    """Camera height of the room loop, metres."""
    room_pitch_deg: float = 10.0
    """Downward pitch of the room camera, degrees."""
    heading_deg: float = 0.0
    """Spiral: direction of the first leg, degrees from +x about the vertical (the spiral turns about the pad, so
    it still ends over it); room: angle on the ellipse where the loop starts, degrees."""
    oscillation_phase_deg: float = 0.0
    """Phase added to the yaw and tilt oscillations, degrees."""


def _spiral_waypoints(cfg: TrajectoryConfig, seconds: float) -> np.ndarray:
    """(K, 3) waypoints: corners and mid-leg points of an inward square spiral ending over (0, 0)."""
    length = max(cfg.speed_m_s * seconds, 1e-3)
    n_legs = int(np.clip(round(length / cfg.leg_length_m), 1, 12))
    # Legs shrink linearly to half the first one's length; their sum is the path length.
    rel = np.linspace(1.0, 0.5, n_legs)
    legs = rel * length / rel.sum()
    dirs = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    pts = [np.zeros(2)]
    for k, leg in enumerate(legs):
        d = dirs[k % 4]
        pts.append(pts[-1] + 0.5 * leg * d)
        pts.append(pts[-1] + 0.5 * leg * d)
    xy = np.array(pts) - pts[-1]
    if cfg.heading_deg:
        c, s_ = np.cos(np.deg2rad(cfg.heading_deg)), np.sin(np.deg2rad(cfg.heading_deg))
        xy = xy @ np.array([[c, s_], [-s_, c]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
    drop = min(cfg.descent_ratio * length, cfg.start_altitude_m - cfg.end_altitude_m)
    z = cfg.end_altitude_m + drop * (1.0 - s / s[-1])
    return np.column_stack([xy, z])


def _room_waypoints(cfg: TrajectoryConfig, seconds: float) -> np.ndarray:
    rx, ry = cfg.room_radii_m
    circ = np.pi * (3 * (rx + ry) - np.sqrt((3 * rx + ry) * (rx + 3 * ry)))  # Ramanujan
    angle = 2 * np.pi * cfg.speed_m_s * seconds / circ
    th = np.linspace(0.0, angle, max(8, int(np.ceil(angle / 0.1)) + 1)) + np.deg2rad(cfg.heading_deg)
    return np.column_stack([rx * np.cos(th), ry * np.sin(th), np.full_like(th, cfg.room_height_m)])


class RigTrajectory:
    """Body (IMU) pose, velocity, acceleration and rates as functions of time in seconds."""

    def __init__(self, cfg: TrajectoryConfig, seconds: float, T_cam_imu: np.ndarray = np.eye(4)):
        self.cfg = cfg
        self.seconds = float(seconds)
        self.T_cam_imu = np.asarray(T_cam_imu, np.float64)
        self.T_imu_cam = invert_pose(self.T_cam_imu)
        wp = _spiral_waypoints(cfg, seconds) if cfg.shape is TrajectoryShape.SPIRAL_LANDING else _room_waypoints(cfg, seconds)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(wp, axis=0), axis=1))])
        t_knots = s / s[-1] * self.seconds
        # Bob: sampled into the spline so position, velocity and acceleration stay one consistent C2 function.
        t_dense = np.linspace(0.0, self.seconds, max(len(wp), int(self.seconds * 50) + 2))
        base = CubicSpline(t_knots, wp, axis=0)(t_dense)
        base[:, 2] += cfg.bob_amplitude_m * np.sin(2 * np.pi * 0.5 * t_dense)
        self._spline = CubicSpline(t_dense, base, axis=0)

    # ---------------------------------------------------------------- rotation
    def camera_rotation(self, t) -> Rotation:
        """Orientation of the camera, ``R_world_cam``."""
        t = np.atleast_1d(np.asarray(t, np.float64))
        c = self.cfg
        w = 2 * np.pi * c.oscillation_hz
        ph = np.deg2rad(c.oscillation_phase_deg)
        yaw = np.deg2rad(c.yaw_rate_deg_s) * t + np.deg2rad(c.yaw_amplitude_deg) * np.sin(w * t + ph)
        tilt_a = np.deg2rad(c.tilt_amplitude_deg) * np.sin(1.3 * w * t + 0.5 + ph)
        tilt_b = np.deg2rad(c.tilt_amplitude_deg) * np.sin(0.9 * w * t + 1.7 + ph)
        if c.shape is TrajectoryShape.SPIRAL_LANDING:
            base = Rotation.from_matrix(_R_DOWN)
            world = Rotation.from_euler("zxy", np.column_stack([yaw, tilt_a, tilt_b]).reshape(-1, 3))
            return world * base
        # Room: heading follows the outward radial direction of the ellipse.
        p = self._spline(t)
        heading = np.arctan2(p[:, 1], p[:, 0]) + yaw
        world = Rotation.from_euler("z", heading[:, None])
        cam = Rotation.from_euler("xz", np.column_stack([-np.deg2rad(c.room_pitch_deg) + tilt_a, tilt_b]))
        return world * Rotation.from_matrix(_R_FORWARD) * cam

    def body_rotation(self, t) -> Rotation:
        """``R_world_body = R_world_cam @ R_cam_imu``."""
        return self.camera_rotation(t) * Rotation.from_matrix(self.T_cam_imu[:3, :3])

    # ------------------------------------------------------------- kinematics
    def body_position(self, t) -> np.ndarray:
        return self._spline(np.atleast_1d(np.asarray(t, np.float64)))

    def body_velocity(self, t) -> np.ndarray:
        return self._spline(np.atleast_1d(np.asarray(t, np.float64)), 1)

    def body_acceleration(self, t) -> np.ndarray:
        return self._spline(np.atleast_1d(np.asarray(t, np.float64)), 2)

    def body_rates(self, t) -> np.ndarray:
        """Angular velocity of B relative to the world, expressed in B, rad/s (N, 3)."""
        t = np.atleast_1d(np.asarray(t, np.float64))
        r0 = self.body_rotation(t - _DT_RATE)
        r1 = self.body_rotation(t + _DT_RATE)
        return (r0.inv() * r1).as_rotvec() / (2 * _DT_RATE)

    # ------------------------------------------------------------------ poses
    def body_poses(self, t) -> np.ndarray:
        """(N, 4, 4) ``T_world_body``."""
        t = np.atleast_1d(np.asarray(t, np.float64))
        T = np.zeros((t.size, 4, 4))
        T[:, :3, :3] = self.body_rotation(t).as_matrix()
        T[:, :3, 3] = self.body_position(t)
        T[:, 3, 3] = 1.0
        return T

    def camera_poses(self, t) -> np.ndarray:
        """(N, 4, 4) ``T_world_cam = T_world_body @ T_imu_cam``."""
        return self.body_poses(t) @ self.T_imu_cam

    def ground_truth(self, t_us: np.ndarray) -> Trajectory:
        """Camera ground truth at the given microsecond times."""
        return Trajectory.from_matrices(t_us, self.camera_poses(np.asarray(t_us, np.float64) * 1e-6))
