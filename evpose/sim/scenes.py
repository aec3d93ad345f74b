"""Triangle-mesh scenes: static geometry with per-face appearance, moving objects, and the true edges.

A :class:`Scene` holds one static mesh (everything the map should contain)
plus :class:`DynamicObject` meshes that move with time and are absent from the
map. Every face carries an albedo (0..1), a procedural texture kind and a light
group; the renderer multiplies a face's shaded albedo by its group's gain at
time ``t`` (HDR regions, lights switching off, flicker).

``edges`` are the creases and boundaries of the static geometry (box edges,
box-ground contact lines, the pad border) in world coordinates; ``albedo_edges``
are the painted boundaries (the pad marker) that only appearance reveals.
World frame: z up, ground at z = 0, metres.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


class Texture(enum.IntEnum):
    """Procedural texture of a face; evaluated at the hit point by the renderer (render.py)."""

    NONE = 0
    NOISE = 1
    """Value noise on a square grid of ``texture_scale`` metres, contrast ``texture_amp``."""
    H_MARKER = 2
    """A bright 'H' landing marker centred at ``texture_center`` (xy), size ``texture_scale`` metres."""


# Box corner order: bit 0 -> x, bit 1 -> y, bit 2 -> z.
_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
# Faces as quads (outward orientation does not matter: shading is two-sided).
_BOX_QUADS = {"-x": (0, 2, 6, 4), "+x": (1, 3, 7, 5), "-y": (0, 1, 5, 4), "+y": (2, 3, 7, 6), "-z": (0, 1, 3, 2), "+z": (4, 5, 7, 6)}


@dataclass
class MeshPart:
    """Triangles with per-face appearance; the building block of scenes."""

    vertices: np.ndarray
    """(V, 3) float64, metres."""
    triangles: np.ndarray
    """(F, 3) int32 vertex indices."""
    albedo: np.ndarray
    """(F,) float64 reflectance 0..1."""
    texture: np.ndarray
    """(F,) int32 :class:`Texture` kind."""
    group: np.ndarray
    """(F,) int32 light group (0 = ordinary daylight)."""
    texture_scale: np.ndarray
    """(F,) float64 texture cell size / marker size, metres."""
    texture_amp: np.ndarray
    """(F,) float64 texture contrast 0..1 (for Texture.NOISE) or marker albedo (Texture.H_MARKER)."""
    texture_center: np.ndarray
    """(F, 2) float64 xy centre of a marker, metres."""

    @classmethod
    def empty(cls) -> "MeshPart":
        return cls(np.zeros((0, 3)), np.zeros((0, 3), np.int32), np.zeros(0), np.zeros(0, np.int32), np.zeros(0, np.int32), np.zeros(0), np.zeros(0), np.zeros((0, 2)))

    @property
    def n_faces(self) -> int:
        return int(self.triangles.shape[0])

    def face_normals(self) -> np.ndarray:
        v = self.vertices[self.triangles]
        n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def face_areas(self) -> np.ndarray:
        v = self.vertices[self.triangles]
        return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)

    def transformed(self, T: np.ndarray) -> "MeshPart":
        """A copy with vertices mapped by the 4x4 rigid transform ``T``."""
        v = self.vertices @ T[:3, :3].T + T[:3, 3]
        return MeshPart(v, self.triangles, self.albedo, self.texture, self.group, self.texture_scale, self.texture_amp, self.texture_center)

    @staticmethod
    def concatenate(parts: list["MeshPart"]) -> "MeshPart":
        parts = [p for p in parts if p.n_faces]
        if not parts:
            return MeshPart.empty()
        offsets = np.cumsum([0] + [p.vertices.shape[0] for p in parts[:-1]])
        return MeshPart(
            np.concatenate([p.vertices for p in parts]),
            np.concatenate([p.triangles + o for p, o in zip(parts, offsets)]).astype(np.int32),
            *(np.concatenate([getattr(p, a) for p in parts]) for a in ("albedo", "texture", "group", "texture_scale", "texture_amp", "texture_center")),
        )


def _part(vertices, quads, albedo, texture=Texture.NONE, group=0, scale=1.0, amp=0.0, center=(0.0, 0.0)) -> MeshPart:
    tris = []
    for a, b, c, d in quads:
        tris += [(a, b, c), (a, c, d)]
    f = len(tris)
    return MeshPart(
        np.asarray(vertices, np.float64),
        np.asarray(tris, np.int32).reshape(-1, 3),
        np.full(f, float(albedo)),
        np.full(f, int(texture), np.int32),
        np.full(f, int(group), np.int32),
        np.full(f, float(scale)),
        np.full(f, float(amp)),
        np.tile(np.asarray(center, np.float64), (f, 1)),
    )


def box_corners(center, size, yaw: float = 0.0) -> np.ndarray:
    """(8, 3) corners of a box standing on ``center[2]`` (its bottom), rotated by ``yaw`` (rad) about z."""
    cx, cy, z0 = center
    sx, sy, sz = size
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.zeros((8, 3))
    for i in range(8):
        lx = (sx / 2) * (1 if i & 1 else -1)
        ly = (sy / 2) * (1 if i & 2 else -1)
        out[i] = (cx + c * lx - s * ly, cy + s * lx + c * ly, z0 + (sz if i & 4 else 0.0))
    return out


def box_part(center, size, albedo, yaw=0.0, bottom=False, top_texture=Texture.NONE, group=0, scale=1.0, amp=0.0, side_albedo=None) -> MeshPart:
    """A box mesh; the bottom face is left out unless ``bottom`` (it rests on the ground and is never seen)."""
    v = box_corners(center, size, yaw)
    sides = [_part(v, [_BOX_QUADS[k] for k in ("-x", "+x", "-y", "+y") + (("-z",) if bottom else ())], albedo if side_albedo is None else side_albedo, group=group)]
    sides.append(_part(v, [_BOX_QUADS["+z"]], albedo, top_texture, group, scale, amp, center[:2]))
    return MeshPart.concatenate(sides)


def box_edges(center, size, yaw=0.0) -> np.ndarray:
    """(12, 2, 3) edge segments of a box (its bottom edges are the ground contact lines)."""
    v = box_corners(center, size, yaw)
    return np.stack([np.stack([v[a], v[b]]) for a, b in _BOX_EDGES])


def quad_part(corners, albedo, texture=Texture.NONE, group=0, scale=1.0, amp=0.0) -> MeshPart:
    return _part(corners, [(0, 1, 2, 3)], albedo, texture, group, scale, amp)


def h_marker_edges(center_xy, size: float, z: float) -> np.ndarray:
    """(12, 2, 3) boundary segments of the 'H' painted by :attr:`Texture.H_MARKER` (same geometry as render.py)."""
    cx, cy = center_xy
    h = size / 2  # half height of the H
    w = size * 0.4  # half width
    bar = size * 0.12  # half thickness of the posts and of the crossbar
    xo, xi = w, w - 2 * bar
    pts = [(-xo, -h), (-xi, -h), (-xi, -bar), (xi, -bar), (xi, -h), (xo, -h), (xo, h), (xi, h), (xi, bar), (-xi, bar), (-xi, h), (-xo, h)]
    pts = [(cx + px, cy + py, z) for px, py in pts]
    return np.array([[pts[i], pts[(i + 1) % len(pts)]] for i in range(len(pts))])


@dataclass
class DynamicObject:
    """A mesh (in its own frame) moving as ``pose(t_s) -> 4x4 T_world_object``; never part of the map."""

    name: str
    mesh: MeshPart
    pose: Callable[[float], np.ndarray]


@dataclass
class Scene:
    """Static mesh + moving objects + lights + true edges, all in the world frame."""

    name: str
    static: MeshPart
    edges: np.ndarray
    """(M, 2, 3) creases and boundaries of the static geometry, metres."""
    albedo_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    """(K, 2, 3) painted boundaries (marker) on static faces, metres."""
    dynamic: list[DynamicObject] = field(default_factory=list)
    sun_direction: np.ndarray = field(default_factory=lambda: np.array([0.4, 0.25, 1.0]) / np.linalg.norm([0.4, 0.25, 1.0]))
    """Unit vector towards the light (Lambertian), world frame."""
    ambient: float = 0.35
    """Light reaching every face regardless of orientation, relative to the sun's 1.0."""
    background: float = 0.6
    """Linear intensity of rays that hit nothing (sky)."""
    group_gain: Callable[[float], np.ndarray] | None = None
    """t_s -> (G,) gain per light group; None means one group with gain 1."""
    n_groups: int = 1
    closed: bool = False
    """True for a closed room: every upward ray leaves through the ceiling."""

    def gains(self, t_s: float) -> np.ndarray:
        if self.group_gain is None:
            return np.ones(self.n_groups)
        return np.asarray(self.group_gain(t_s), dtype=np.float64)

    def mesh_at(self, t_s: float) -> tuple[MeshPart, np.ndarray]:
        """Static + posed dynamic meshes at time ``t_s``, and (F,) object index per face (-1 static)."""
        parts = [self.static]
        owner = [np.full(self.static.n_faces, -1, np.int32)]
        for i, obj in enumerate(self.dynamic):
            parts.append(obj.mesh.transformed(obj.pose(t_s)))
            owner.append(np.full(obj.mesh.n_faces, i, np.int32))
        return MeshPart.concatenate(parts), np.concatenate(owner)
