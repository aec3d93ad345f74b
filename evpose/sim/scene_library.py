"""The scenes evpose simulates: an urban landing site and an indoor room, with optional conditions.

Numbers here define the demo world; they are plain geometry (metres) chosen so
the square-spiral landing (trajectories.py) sees the pad, the crates around it
and, from higher up, the buildings; nothing in the flight path intersects them.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from evpose.sim.scenes import DynamicObject, MeshPart, Scene, Texture, box_edges, box_part, h_marker_edges, quad_part


class SceneName(str, enum.Enum):
    LANDING = "landing"
    INDOOR = "indoor"


@dataclass(frozen=True)
class SceneOptions:
    """Condition switches applied on top of a scene (the robustness variants)."""

    hdr: bool = False
    """One building and one crate 15x brighter (switching to 0.3x at ``hdr_switch_s``), one of each 20x darker."""
    hdr_switch_s: float = 1.0
    """Time the bright building's light switches off, seconds."""
    flicker_hz: float = 0.0
    """Frequency of a light flickering on the crates and one building, Hz (0 = off)."""
    flicker_depth: float = 0.5
    """Relative modulation of the flickering light, 0..1."""
    dynamic: bool = False
    """Add a rotating fan and two walking people-sized boxes (absent from the map)."""
    ground_texture: bool = False
    """Fine value-noise texture on the ground (events on no map contour)."""
    ground_texture_scale_m: float = 0.05
    """Cell size of the ground texture, metres."""
    ground_texture_contrast: float = 0.5
    """Contrast of the ground texture, 0..1."""


# (centre x, centre y, size x, size y, height, albedo, yaw rad)
_BUILDINGS = [
    (8.0, 3.0, 4.0, 6.0, 4.0, 0.75, 0.0),
    (-7.0, -6.0, 5.0, 4.0, 2.5, 0.5, 0.2),
    (-8.0, 6.0, 3.0, 3.0, 5.5, 0.85, -0.1),
    (4.0, -9.0, 6.0, 3.0, 3.0, 0.6, 0.0),
    (11.0, -4.0, 3.0, 4.0, 2.0, 0.45, 0.3),
    (0.0, 11.0, 5.0, 3.0, 3.5, 0.65, 0.0),
]
_CRATES = [
    (2.6, 1.2, 0.8, 0.6, 0.5, 0.7, 0.3),
    (-2.2, -2.4, 1.0, 1.0, 0.7, 0.55, -0.2),
    (-2.8, 1.9, 0.6, 1.2, 0.4, 0.8, 0.0),
]
# Street furniture around the pad (vans, kiosks, walls, containers) so the approach always sees structure.
_CLUTTER = [
    (-5.5, -1.2, 4.5, 1.8, 1.5, 0.8, 0.1),
    (-4.0, 3.5, 2.0, 2.0, 2.2, 0.4, 0.4),
    (4.5, 4.5, 1.2, 3.0, 1.0, 0.9, -0.3),
    (5.5, -3.5, 2.5, 2.5, 2.5, 0.3, 0.0),
    (-1.0, -5.5, 6.0, 0.4, 1.2, 0.7, 0.0),
    (1.0, 5.5, 1.5, 1.5, 0.8, 0.55, 0.7),
    (-8.5, 1.0, 1.0, 4.0, 1.8, 0.6, 0.0),
    (3.5, -6.5, 2.0, 1.0, 1.4, 0.85, 0.5),
]
PAD_SIZE_M = 3.0
PAD_HEIGHT_M = 0.15
PAD_ALBEDO = 0.2
MARKER_ALBEDO = 0.65
MARKER_SIZE_M = 2.0
GROUND_HALF_M = 40.0
FAN_XY = (1.6, -1.2)

_G_DAY, _G_BRIGHT, _G_DARK, _G_FLICKER = 0, 1, 2, 3


def _boxes(rows, group_of) -> tuple[list[MeshPart], list[np.ndarray]]:
    parts, edges = [], []
    for i, (x, y, sx, sy, h, alb, yaw) in enumerate(rows):
        parts.append(box_part((x, y, 0.0), (sx, sy, h), alb, yaw, group=group_of(i)))
        edges.append(box_edges((x, y, 0.0), (sx, sy, h), yaw))
    return parts, edges


def _fan(center_xy, rate_hz: float) -> list[DynamicObject]:
    cx, cy = center_xy
    pole = box_part((0.0, 0.0, 0.0), (0.08, 0.08, 1.2), 0.3)
    blades = MeshPart.concatenate([box_part((0.0, 0.0, 1.2), (1.4, 0.14, 0.02), 0.9, yaw=k * np.pi / 3) for k in range(3)])

    def still(t):
        T = np.eye(4)
        T[:2, 3] = (cx, cy)
        return T

    def spin(t):
        a = 2 * np.pi * rate_hz * t
        T = np.eye(4)
        T[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        T[:2, 3] = (cx, cy)
        return T

    return [DynamicObject("fan_pole", pole, still), DynamicObject("fan_blades", blades, spin)]


def _walker(name, albedo, path) -> DynamicObject:
    mesh = box_part((0.0, 0.0, 0.0), (0.5, 0.35, 1.75), albedo)

    def pose(t):
        x, y, yaw = path(t)
        T = np.eye(4)
        T[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
        T[:2, 3] = (x, y)
        return T

    return DynamicObject(name, mesh, pose)


def landing_scene(opts: SceneOptions = SceneOptions()) -> Scene:
    """Ground, a raised landing pad with an 'H' marker, crates around it and buildings further out."""
    g = GROUND_HALF_M
    ground_tex = Texture.NOISE if opts.ground_texture else Texture.NONE
    parts = [quad_part([(-g, -g, 0.0), (g, -g, 0.0), (g, g, 0.0), (-g, g, 0.0)], 0.35, ground_tex, _G_DAY, opts.ground_texture_scale_m, opts.ground_texture_contrast)]
    edges = []
    parts.append(box_part((0.0, 0.0, 0.0), (PAD_SIZE_M, PAD_SIZE_M, PAD_HEIGHT_M), PAD_ALBEDO, top_texture=Texture.H_MARKER, scale=MARKER_SIZE_M, amp=MARKER_ALBEDO, side_albedo=0.5))
    edges.append(box_edges((0.0, 0.0, 0.0), (PAD_SIZE_M, PAD_SIZE_M, PAD_HEIGHT_M)))
    bright = _G_BRIGHT if opts.hdr else _G_DAY
    dark = _G_DARK if opts.hdr else _G_DAY
    flick = _G_FLICKER if opts.flicker_hz > 0 else _G_DAY
    p, e = _boxes(_BUILDINGS, lambda i: {0: bright, 1: dark, 5: flick}.get(i, _G_DAY))
    parts += p
    edges += e
    # Crates next to the pad carry the conditions too, so short final approaches see them.
    p, e = _boxes(_CRATES, lambda i: {0: bright, 1: dark}.get(i, flick) if opts.hdr else flick)
    parts += p
    edges += e
    p, e = _boxes(_CLUTTER, lambda i: _G_DAY)
    parts += p
    edges += e

    def gains(t: float) -> np.ndarray:
        out = np.ones(4)
        if opts.hdr:
            # A smooth 50 ms switch: real lamps dim over milliseconds, and a step would put every event at one time.
            s = np.clip((t - opts.hdr_switch_s) / 0.05, 0.0, 1.0)
            s = s * s * (3 - 2 * s)
            out[_G_BRIGHT] = 15.0 * (1 - s) + 0.3 * s
            out[_G_DARK] = 0.05
        if opts.flicker_hz > 0:
            out[_G_FLICKER] = 1.0 + opts.flicker_depth * np.sin(2 * np.pi * opts.flicker_hz * t)
        return out

    dynamic = []
    if opts.dynamic:
        # Placed next to the pad so the final approach sees them; paths clear the pad and the crates.
        dynamic += _fan(FAN_XY, 1.5)
        dynamic.append(_walker("walker_a", 0.25, lambda t: (0.5 + 1.2 * np.sin(0.8 * t), 1.9, 0.0)))
        dynamic.append(_walker("walker_b", 0.85, lambda t: (-2.0, 0.3 + 1.0 * np.sin(0.6 * t + 1.0), np.pi / 2)))
    return Scene(
        name="landing",
        static=MeshPart.concatenate(parts),
        edges=np.concatenate(edges),
        albedo_edges=h_marker_edges((0.0, 0.0), MARKER_SIZE_M, PAD_HEIGHT_M),
        dynamic=dynamic,
        group_gain=gains,
        n_groups=4,
    )


# Indoor room: x in [-4, 4], y in [-3, 3], z in [0, 3].
ROOM = (4.0, 3.0, 3.0)
_FURNITURE = [
    # (x, y, z0, sx, sy, sz, albedo)
    (2.6, 0.5, 0.0, 1.6, 0.9, 0.75, 0.35),  # table
    (-3.6, -1.5, 0.0, 0.6, 1.2, 1.8, 0.2),  # cabinet
    (0.5, 2.75, 0.0, 2.0, 0.4, 2.0, 0.85),  # shelf
    (-1.5, -2.45, 0.0, 2.0, 0.9, 0.8, 0.15),  # sofa
    (-2.6, 1.6, 0.0, 0.5, 0.5, 0.5, 0.9),  # box
    (-3.99, 0.8, 1.2, 0.02, 1.2, 0.8, 0.95),  # picture on the -x wall
    (1.5, -2.99, 0.0, 0.9, 0.02, 2.1, 0.1),  # door on the -y wall
    (3.99, -1.2, 1.0, 0.02, 1.6, 1.0, 0.05),  # screen on the +x wall
]


def indoor_scene(opts: SceneOptions = SceneOptions()) -> Scene:
    """A closed room (floor, four walls, ceiling) with furniture, pictures and a door."""
    X, Y, Z = ROOM
    c = np.array([[x, y, z] for z in (0.0, Z) for y in (-Y, Y) for x in (-X, X)])  # same bit order as boxes
    floor_tex = Texture.NOISE if opts.ground_texture else Texture.NONE
    parts = [
        quad_part(c[[0, 1, 3, 2]], 0.4, floor_tex, 0, opts.ground_texture_scale_m, opts.ground_texture_contrast),
        quad_part(c[[4, 5, 7, 6]], 0.8),
        quad_part(c[[0, 2, 6, 4]], 0.7),
        quad_part(c[[1, 3, 7, 5]], 0.6),
        quad_part(c[[0, 1, 5, 4]], 0.75),
        quad_part(c[[2, 3, 7, 6]], 0.55),
    ]
    edges = [box_edges((0.0, 0.0, 0.0), (2 * X, 2 * Y, Z))]
    for x, y, z0, sx, sy, sz, alb in _FURNITURE:
        parts.append(box_part((x, y, z0), (sx, sy, sz), alb, bottom=z0 > 0))
        edges.append(box_edges((x, y, z0), (sx, sy, sz)))
    dynamic = []
    if opts.dynamic:
        dynamic.append(_walker("walker_a", 0.3, lambda t: (0.0 + 1.5 * np.sin(0.6 * t), 2.0, 0.0)))
    sun = np.array([0.3, -0.2, 1.0])
    return Scene(
        name="indoor",
        static=MeshPart.concatenate(parts),
        edges=np.concatenate(edges),
        dynamic=dynamic,
        sun_direction=sun / np.linalg.norm(sun),
        ambient=0.5,
        background=0.5,
        closed=True,
    )


def build_scene(name: SceneName, opts: SceneOptions = SceneOptions()) -> Scene:
    return {SceneName.LANDING: landing_scene, SceneName.INDOOR: indoor_scene}[SceneName(name)](opts)
