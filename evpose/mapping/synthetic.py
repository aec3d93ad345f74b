"""Synthetic raw scans with known edges (boxes on a ground plane, a wall with a window) for tests and benchmarks.

Surfaces are sampled uniformly (area-proportional, ``density`` points per m^2) and
disturbed with range noise along the ray from a scanner position, as a LiDAR would.
Intensity is a per-surface albedo. True edges are every edge of every box (including
where a box stands on the ground) and the border of the window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class SyntheticScan:
    """A raw cloud with its ground-truth edges."""

    points: np.ndarray
    """Positions, float64 (N, 3), metres (z up, ground at z = 0)."""
    intensity: np.ndarray
    """Albedo per point in [0, 1], float64 (N,)."""
    edges: np.ndarray
    """True edge segments, float64 (M, 2, 3), metres."""


@dataclass(frozen=True)
class Box:
    """An upright box standing on the ground."""

    center_xy: tuple[float, float]
    """Footprint centre, metres."""
    size: tuple[float, float, float]
    """Extent along its own x, y and height, metres."""
    yaw_deg: float = 0.0
    """Rotation about z, degrees."""
    albedo_top: float = 0.8
    """Intensity of the top face."""
    albedo_side: float = 0.55
    """Intensity of the side faces."""


DEFAULT_BOXES = (
    Box((-1.2, -0.8), (1.0, 0.8, 0.5)),
    Box((1.0, 0.9), (0.8, 1.2, 0.8), yaw_deg=30.0, albedo_top=0.1, albedo_side=0.2),
    Box((0.9, -1.3), (0.6, 0.6, 0.3), yaw_deg=-15.0),
)


def _rect(rng, origin, u, v, density):
    area = np.linalg.norm(u) * np.linalg.norm(v)
    n = int(rng.poisson(area * density))
    s = rng.random((n, 2))
    return origin + s[:, :1] * u + s[:, 1:] * v


def _box_frame(b: Box):
    c, s = np.cos(np.radians(b.yaw_deg)), np.sin(np.radians(b.yaw_deg))
    ex = np.array([c, s, 0.0]) * b.size[0]
    ey = np.array([-s, c, 0.0]) * b.size[1]
    ez = np.array([0.0, 0.0, b.size[2]])
    o = np.array([b.center_xy[0], b.center_xy[1], 0.0]) - 0.5 * ex - 0.5 * ey
    return o, ex, ey, ez


def _inside_footprint(p, b: Box):
    o, ex, ey, _ = _box_frame(b)
    d = p[:, :2] - o[:2]
    a = d @ ex[:2] / (ex[:2] @ ex[:2])
    c = d @ ey[:2] / (ey[:2] @ ey[:2])
    return (a >= 0) & (a <= 1) & (c >= 0) & (c <= 1)


def _box_edges(b: Box) -> np.ndarray:
    o, ex, ey, ez = _box_frame(b)
    corners = [o, o + ex, o + ex + ey, o + ey]
    segs = []
    for z in (np.zeros(3), ez):
        for i in range(4):
            segs.append((corners[i] + z, corners[(i + 1) % 4] + z))
    for i in range(4):
        segs.append((corners[i], corners[i] + ez))
    return np.array(segs, dtype=np.float64)


def _range_noise(rng, p, scanner, sigma):
    if sigma <= 0 or p.shape[0] == 0:
        return p
    ray = p - scanner
    ray /= np.linalg.norm(ray, axis=1, keepdims=True)
    return p + ray * rng.normal(0.0, sigma, (p.shape[0], 1))


def boxes_on_ground(
    boxes: tuple[Box, ...] = DEFAULT_BOXES,
    half_extent: float = 3.0,
    density: float = 2500.0,
    noise_m: float = 0.005,
    seed: int = 0,
    scanner=(0.0, 0.0, 6.0),
    ground_albedo: float = 0.35,
) -> SyntheticScan:
    """Boxes on a square ground of side ``2 * half_extent`` m; the ground's border is the scan's rim (no edge)."""
    rng = np.random.default_rng(seed)
    L = half_extent
    parts, albedo = [], []
    g = _rect(rng, np.array([-L, -L, 0.0]), np.array([2 * L, 0, 0]), np.array([0, 2 * L, 0]), density)
    for b in boxes:
        g = g[~_inside_footprint(g, b)]
    parts.append(g)
    albedo.append(np.full(g.shape[0], ground_albedo))
    edges = []
    for b in boxes:
        o, ex, ey, ez = _box_frame(b)
        faces = [(o + ez, ex, ey, b.albedo_top)]
        faces += [(o, ex, ez, b.albedo_side), (o + ey, ex, ez, b.albedo_side),
                  (o, ey, ez, b.albedo_side), (o + ex, ey, ez, b.albedo_side)]
        for origin, u, v, a in faces:
            p = _rect(rng, origin, u, v, density)
            parts.append(p)
            albedo.append(np.full(p.shape[0], a))
        edges.append(_box_edges(b))
    pts = np.concatenate(parts)
    inten = np.concatenate(albedo) + rng.normal(0.0, 0.02, pts.shape[0])
    pts = _range_noise(rng, pts, np.asarray(scanner, np.float64), noise_m)
    perm = rng.permutation(pts.shape[0])
    edges_arr = np.concatenate(edges) if edges else np.zeros((0, 2, 3))
    return SyntheticScan(pts[perm], np.clip(inten[perm], 0, 1), edges_arr)


def wall_with_window(
    width: float = 4.0,
    height: float = 3.0,
    window: tuple[float, float, float, float] = (1.5, 1.0, 1.0, 0.8),
    density: float = 2500.0,
    noise_m: float = 0.005,
    seed: int = 0,
) -> SyntheticScan:
    """A single vertical plane (x-z) with a rectangular see-through window ``(x0, z0, w, h)``.

    The window border is the only true edge; the plane's outer border is where the scan stops.
    """
    rng = np.random.default_rng(seed)
    p = _rect(rng, np.zeros(3), np.array([width, 0, 0]), np.array([0, 0, height]), density)
    x0, z0, w, h = window
    hole = (p[:, 0] > x0) & (p[:, 0] < x0 + w) & (p[:, 2] > z0) & (p[:, 2] < z0 + h)
    p = p[~hole]
    p = _range_noise(rng, p, np.array([width / 2, -5.0, height / 2]), noise_m)
    c = [np.array([x0, 0, z0]), np.array([x0 + w, 0, z0]), np.array([x0 + w, 0, z0 + h]), np.array([x0, 0, z0 + h])]
    edges = np.array([(c[i], c[(i + 1) % 4]) for i in range(4)], dtype=np.float64)
    inten = np.clip(0.5 + rng.normal(0, 0.02, p.shape[0]), 0, 1)
    return SyntheticScan(p, inten, edges)


def painted_plane(
    size: float = 3.0,
    panel: tuple[float, float, float, float] = (0.9, 0.8, 1.2, 1.0),
    albedo: float = 0.7,
    panel_albedo: float = 0.2,
    density: float = 400.0,
    noise_m: float = 0.005,
    intensity_noise: float = 0.03,
    panel_offset_m: float = 0.0,
    seed: int = 0,
) -> SyntheticScan:
    """A horizontal square plane (side ``size`` m, z = 0) with a painted rectangle ``(x0, y0, w, h)`` of another albedo.

    ``panel_offset_m`` > 0 makes the rectangle a thin panel standing that far above the
    plane (a picture on a wall) with the plane still sampled underneath it, as a simulator
    sampling every surface produces. The rectangle's border is the only true edge (the
    plane's own border is the scan's rim). Intensity noise is Gaussian, ``intensity_noise``.
    """
    rng = np.random.default_rng(seed)
    p = _rect(rng, np.zeros(3), np.array([size, 0, 0]), np.array([0, size, 0]), density)
    x0, y0, w, h = panel
    inside = (p[:, 0] > x0) & (p[:, 0] < x0 + w) & (p[:, 1] > y0) & (p[:, 1] < y0 + h)
    inten = np.where(inside, panel_albedo, albedo)
    if panel_offset_m > 0:
        top = _rect(rng, np.array([x0, y0, panel_offset_m]), np.array([w, 0, 0]), np.array([0, h, 0]), density)
        p = np.concatenate([p, top])
        inten = np.concatenate([np.full(inside.size, albedo), np.full(top.shape[0], panel_albedo)])
    p = _range_noise(rng, p, np.array([size / 2, size / 2, 4.0]), noise_m)
    inten = np.clip(inten + rng.normal(0.0, intensity_noise, p.shape[0]), 0, 1)
    c = [np.array([x0, y0, 0.0]), np.array([x0 + w, y0, 0.0]), np.array([x0 + w, y0 + h, 0.0]), np.array([x0, y0 + h, 0.0])]
    edges = np.array([(c[i], c[(i + 1) % 4]) for i in range(4)], dtype=np.float64)
    return SyntheticScan(p, inten, edges)


def cabinet_before_wall(
    gap_m: float = 0.1,
    size: tuple[float, float, float] = (0.6, 1.2, 1.2),
    density: float = 100.0,
    noise_m: float = 0.005,
    seed: int = 0,
) -> SyntheticScan:
    """A cabinet (box, all five faces sampled, its back too) standing ``gap_m`` m in front of a wall, on a floor.

    The room-scan case: a simulator (or a scan merged from many stations) samples the
    cabinet's back face in the narrow gap, so a point's neighbours mix two parallel layers a
    few centimetres apart. Floor 3 x 3 m (x in [0, 3], y in [-1.5, 1.5]), wall 3 x 2 m in the
    plane x = 0; the cabinet's back face is at x = ``gap_m``. True edges: the cabinet's 12
    edges and the wall-floor line. Range noise along the surface normals, Gaussian.
    """
    rng = np.random.default_rng(seed)
    sx, sy, sz = size
    floor = _rect(rng, np.array([0.0, -1.5, 0.0]), np.array([3.0, 0, 0]), np.array([0, 3.0, 0]), density)
    o = np.array([gap_m, -sy / 2, 0.0])
    ex, ey, ez = np.array([sx, 0, 0]), np.array([0, sy, 0]), np.array([0, 0, sz])
    inside = (floor[:, 0] > gap_m) & (floor[:, 0] < gap_m + sx) & (np.abs(floor[:, 1]) < sy / 2)
    floor = floor[~inside]
    wall = _rect(rng, np.array([0.0, -1.5, 0.0]), np.array([0, 3.0, 0]), np.array([0, 0, 2.0]), density)
    faces = [(o + ez, ex, ey, np.array([0, 0, 1.0])), (o, ey, ez, np.array([1.0, 0, 0])),
             (o + ex, ey, ez, np.array([1.0, 0, 0])), (o, ex, ez, np.array([0, 1.0, 0])),
             (o + ey, ex, ez, np.array([0, 1.0, 0]))]
    parts = [(floor, np.array([0, 0, 1.0]), 0.4), (wall, np.array([1.0, 0, 0]), 0.7)]
    parts += [(_rect(rng, origin, u, v, density), n, 0.3) for origin, u, v, n in faces]
    pts = np.concatenate([p + n * rng.normal(0.0, noise_m, (p.shape[0], 1)) for p, n, _ in parts])
    inten = np.concatenate([np.full(p.shape[0], a) for p, _, a in parts]) + rng.normal(0.0, 0.02, pts.shape[0])
    box = Box((gap_m + sx / 2, 0.0), size)
    edges = np.concatenate([_box_edges(box), [[[0.0, -1.5, 0.0], [0.0, 1.5, 0.0]]]])
    return SyntheticScan(pts, np.clip(inten, 0, 1), edges)
