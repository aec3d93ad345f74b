"""Ray-cast rendering of a :class:`~evpose.sim.scenes.Scene` with open3d, per light group.

Each sensor pixel shoots ``s x s`` stratified sub-pixel rays (supersampling =
box-filter anti-aliasing) through the exact lens model (``calibration.unproject``,
so distortion is the real inverse, not an approximation). A hit is shaded
Lambertian (two-sided) with a sun direction and an ambient term, times the
face's albedo and procedural texture. The output keeps one linear-intensity
image per light group so the caller can apply time-varying group gains
(flicker, lights switching off) without casting rays again.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from evpose.core.camera import CameraCalibration
from evpose.sim.scenes import Scene


@dataclass(frozen=True)
class RenderConfig:
    """How images are rendered."""

    supersampling: int = field(default=3, metadata={"min": 1, "max": 8, "step": 1, "unit": "rays/px per axis"})
    """Sub-pixel rays per pixel along each axis (s x s rays); 3 keeps edges sub-pixel accurate."""
    log_eps: float = field(default=0.01, metadata={"min": 1e-4, "max": 0.1, "unit": "linear intensity"})
    """Offset in ``log(I + eps)``: the darkest intensity the sensor still resolves."""
    threads: int = 0
    """Ray-casting threads for open3d (0 = all cores); per-ray results do not depend on it."""


@nb.njit(cache=True)
def _hash01(ix, iy):
    # Integer hash of a lattice cell -> [0, 1); wrap-around uint64 arithmetic keeps it deterministic.
    h = np.uint64(ix) * np.uint64(0x9E3779B97F4A7C15) ^ np.uint64(iy) * np.uint64(0xC2B2AE3D27D4EB4F)
    h ^= h >> np.uint64(31)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(29)
    return float(h >> np.uint64(11)) / 9007199254740992.0


@nb.njit(cache=True)
def _value_noise(x, y, scale):
    u = x / scale
    v = y / scale
    iu = np.floor(u)
    iv = np.floor(v)
    fu = u - iu
    fv = v - iv
    fu = fu * fu * (3.0 - 2.0 * fu)
    fv = fv * fv * (3.0 - 2.0 * fv)
    a = np.int64(iu)
    b = np.int64(iv)
    n00 = _hash01(a, b)
    n10 = _hash01(a + 1, b)
    n01 = _hash01(a, b + 1)
    n11 = _hash01(a + 1, b + 1)
    return (n00 * (1 - fu) + n10 * fu) * (1 - fv) + (n01 * (1 - fu) + n11 * fu) * fv


@nb.njit(cache=True)
def surface_albedo(x, y, base, kind, scale, amp, cx, cy):
    """Albedo of a face with texture ``kind`` at world point (x, y); mirrors scenes.Texture."""
    if kind == 1:
        return base * (1.0 + amp * (2.0 * _value_noise(x, y, scale) - 1.0))
    if kind == 2:
        lx = abs(x - cx)
        ly = abs(y - cy)
        h = scale / 2
        w = scale * 0.4
        bar = scale * 0.12
        if lx <= w and ly <= h and (lx >= w - 2 * bar or ly <= bar):
            return amp
        return base
    return base


@nb.njit(cache=True)
def albedo_at_points(points, faces, albedo, kind, scale, amp, center):
    """Textured albedo of points lying on the given faces (used for the LiDAR cloud's intensity)."""
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        f = faces[i]
        out[i] = surface_albedo(points[i, 0], points[i, 1], albedo[f], kind[f], scale[f], amp[f], center[f, 0], center[f, 1])
    return out


@nb.njit(cache=True)
def _shade(origin, dirs, t_hit, prim, normals, albedo, kind, group, scale, amp, center, sun, ambient, background, n_groups, spp):
    n_pix = dirs.shape[0] // spp
    out = np.zeros((n_groups, n_pix), np.float32)
    pts = np.full((n_pix, 3), np.nan)
    face = np.full(n_pix, -1, np.int32)
    inv = 1.0 / spp
    for p in range(n_pix):
        for s in range(spp):
            r = p * spp + s
            th = t_hit[r]
            if not np.isfinite(th):
                out[0, p] += background * inv
                continue
            f = prim[r]
            dx = dirs[r, 0]
            dy = dirs[r, 1]
            dz = dirs[r, 2]
            x = origin[0] + th * dx
            y = origin[1] + th * dy
            z = origin[2] + th * dz
            if s == 0:
                pts[p, 0] = x
                pts[p, 1] = y
                pts[p, 2] = z
                face[p] = f
            nx = normals[f, 0]
            ny = normals[f, 1]
            nz = normals[f, 2]
            if nx * dx + ny * dy + nz * dz > 0:  # two-sided: use the side facing the camera
                nx, ny, nz = -nx, -ny, -nz
            lam = nx * sun[0] + ny * sun[1] + nz * sun[2]
            if lam < 0:
                lam = 0.0
            a = surface_albedo(x, y, albedo[f], kind[f], scale[f], amp[f], center[f, 0], center[f, 1])
            out[group[f], p] += a * (ambient + lam) * inv
    return out, pts, face


@dataclass
class RenderOutput:
    """One rendered instant."""

    group_images: np.ndarray
    """(G, H, W) float32 linear intensity contributed by each light group (gain 1)."""
    points: np.ndarray
    """(H*W, 3) world point hit by each pixel's centre ray (NaN on a miss), metres; see ``fresh``."""
    face: np.ndarray
    """(H*W,) index of the face hit (into the mesh of that instant), -1 on a miss."""
    face_owner: np.ndarray
    """(F,) dynamic object index per face, -1 for static faces."""
    centre: np.ndarray
    """(G, H, W) float32 centre-ray values (before supersampling)."""
    mark: np.ndarray
    """(H, W) bool pixels that were supersampled (on an intensity discontinuity or a noise texture)."""
    fresh: np.ndarray
    """(H, W) bool pixels whose centre ray was cast for this render (all for a full render); elsewhere
    ``points``/``face`` still hold an earlier render's hit, whose shade is unchanged but whose position is stale."""
    footprint: np.ndarray | None
    """(H, W) bool image region of the moving objects at this render (None: not boundable)."""


_BAND_PX = 3  # re-cast radius around previous discontinuities; > the 0.5-1 px motion between renders


def cv2_dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    """Boolean dilation with a (2r+1)^2 square."""
    import cv2

    k = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.dilate(mask.astype(np.uint8), k).astype(bool)


def subpixel_pattern(s: int) -> np.ndarray:
    """(s*s, 2) sub-pixel offsets in [-0.5, 0.5): an s x s "rotated grid" / n-rooks pattern.

    Every sample has its own column and row (s*s distinct x and y values) and
    every s x s stratum holds one sample, so an axis-aligned edge sweeping
    the pixel changes its coverage in s*s steps instead of s: events from
    supersampled edges come at evenly spread times, not in bursts.
    """
    n = s * s
    k = np.arange(n)
    x = (k + 0.5) / n
    y = ((k * s) % n + k // s + 0.5) / n
    return np.stack([x, y], axis=1) - 0.5


@nb.njit(cache=True)
def _mark_kernel(img, tex_noise, band, rel_tol):
    g, h, w = img.shape
    mark = tex_noise.copy()
    for y in range(h):
        for x in range(w):
            if mark[y, x] or not band[y, x]:
                continue
            done = False
            for dy in range(-1, 2):
                yy = min(max(y + dy, 0), h - 1)
                for dx in range(-1, 2):
                    xx = min(max(x + dx, 0), w - 1)
                    for k in range(g):
                        v = img[k, y, x]
                        if abs(img[k, yy, xx] - v) > rel_tol * (abs(v) + 1e-6):
                            done = True
                            break
                    if done:
                        break
                if done:
                    break
            mark[y, x] = done
    return mark


def _needs_supersampling(img: np.ndarray, tex_noise: np.ndarray, band: np.ndarray | None = None, rel_tol: float = 1e-6) -> np.ndarray:
    """(H, W) bool: pixels whose 8-neighbourhood is not uniform in any group image, or that see a noise texture.

    A pixel whose own and neighbouring centre rays all return the same shade
    lies inside one uniformly shaded region (flat faces under a directional
    light are uniform unless textured), so its supersampled value equals its
    centre value; only features thinner than a pixel can slip through.
    Only pixels in ``band`` (default: all) are examined.
    """
    if band is None:
        band = np.ones(tex_noise.shape, bool)
    return _mark_kernel(np.ascontiguousarray(img), np.ascontiguousarray(tex_noise), np.ascontiguousarray(band), float(rel_tol))


class Renderer:
    """Casts the rays of one camera into a scene; reuses the ray-casting BVH when nothing moves.

    Adaptive supersampling: one centre ray per pixel first; pixels on an
    intensity discontinuity (or on a noise texture) are re-rendered with the
    full ``s x s`` sub-ray grid. Uniform pixels equal their centre ray, so the
    result equals full supersampling at a fraction of the rays.
    """

    def __init__(self, scene: Scene, calibration: CameraCalibration, config: RenderConfig = RenderConfig()):
        self.scene = scene
        self.calibration = calibration
        self.config = config
        s = int(config.supersampling)
        w, h = calibration.width, calibration.height
        self.sub_offsets = subpixel_pattern(s)  # (spp, 2) pixels
        self.spp = s * s
        ys, xs = np.mgrid[0:h, 0:w]
        self.pixel_uv = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
        self.bearings = calibration.unproject(self.pixel_uv)  # (H*W, 3) centre rays, camera frame
        self._static = None
        self.stats = {"rays": 0, "renders": 0}
        if not scene.dynamic:
            self._static = self._build(scene.static, np.full(scene.static.n_faces, -1, np.int32))

    def _build(self, mesh, owner):
        import open3d as o3d

        rc = o3d.t.geometry.RaycastingScene()
        rc.add_triangles(
            o3d.core.Tensor(mesh.vertices.astype(np.float32)),
            o3d.core.Tensor(mesh.triangles.astype(np.uint32)),
        )
        return rc, mesh, mesh.face_normals(), owner

    def _cast(self, rc, mesh, normals, o, dirs, spp):
        import open3d as o3d

        rays = np.empty((dirs.shape[0], 6), np.float32)
        rays[:, :3] = o
        rays[:, 3:] = dirs
        ans = rc.cast_rays(o3d.core.Tensor(rays), nthreads=int(self.config.threads))
        t_hit = ans["t_hit"].numpy()
        prim = ans["primitive_ids"].numpy().astype(np.int64)
        prim[~np.isfinite(t_hit)] = 0
        self.stats["rays"] += dirs.shape[0]
        sc = self.scene
        return _shade(
            o, dirs, t_hit, prim, normals, mesh.albedo, mesh.texture, mesh.group, mesh.texture_scale, mesh.texture_amp, mesh.texture_center,
            np.asarray(sc.sun_direction, np.float64), float(sc.ambient), float(sc.background), int(sc.n_groups), spp,
        )

    def render(self, T_world_cam: np.ndarray, t_s: float, previous: RenderOutput | None = None) -> RenderOutput:
        """Render at pose ``T_world_cam`` and time ``t_s``.

        ``previous`` (the render of the same camera a moment earlier, with no
        pixel moving more than ~1 px since) lets a static scene re-cast only a
        band of ``_BAND_PX`` pixels around the previous intensity
        discontinuities and the image border: elsewhere each pixel lay inside
        one uniformly shaded region that cannot have changed.
        """
        if self._static is not None:
            rc, mesh, normals, owner = self._static
        else:
            mesh, owner = self.scene.mesh_at(t_s)
            rc, mesh, normals, owner = self._build(mesh, owner)
        footprint = self._dynamic_footprint(T_world_cam, t_s)
        if footprint is None or (previous is not None and previous.footprint is None):
            previous = None  # a moving object too close to bound: cast every pixel
        R = T_world_cam[:3, :3]
        o = T_world_cam[:3, 3].astype(np.float64)
        h, w = self.calibration.height, self.calibration.width
        g = self.scene.n_groups
        band = None
        fresh = np.ones((h, w), bool)
        if previous is None:
            centre, pts, face = self._cast(rc, mesh, normals, o, self.bearings @ R.T, 1)
        else:
            band = cv2_dilate(previous.mark, _BAND_PX)
            band[:_BAND_PX, :] = band[-_BAND_PX:, :] = True
            band[:, :_BAND_PX] = band[:, -_BAND_PX:] = True
            band |= previous.footprint | footprint  # where moving objects were and are
            fresh = band
            idx = np.flatnonzero(band.ravel())
            centre = previous.centre.reshape(g, h * w).copy()
            pts = previous.points.copy()
            face = previous.face.copy()
            centre[:, idx], pts[idx], face[idx] = self._cast(rc, mesh, normals, o, self.bearings[idx] @ R.T, 1)
        img = centre.copy()
        mark = np.zeros((h, w), bool)
        if self.spp > 1:
            tex_noise = np.zeros(h * w, bool)
            hit = face >= 0
            tex_noise[hit] = mesh.texture[face[hit]] == 1
            mark = _needs_supersampling(centre.reshape(g, h, w), tex_noise.reshape(h, w), band)
            idx = np.flatnonzero(mark.ravel())
            if idx.size:
                uv = (self.pixel_uv[idx][:, None, :] + self.sub_offsets[None, :, :]).reshape(-1, 2)
                sub, _, _ = self._cast(rc, mesh, normals, o, self.calibration.unproject(uv) @ R.T, self.spp)
                img[:, idx] = sub
        self.stats["renders"] += 1
        return RenderOutput(img.reshape(g, h, w), pts, face, owner, centre.reshape(g, h, w), mark, fresh, footprint)

    def _dynamic_footprint(self, T_world_cam: np.ndarray, t_s: float) -> np.ndarray | None:
        """(H, W) bool covering every moving object's image (vertex bounding boxes + margin); None if unboundable."""
        h, w = self.calibration.height, self.calibration.width
        out = np.zeros((h, w), bool)
        R, o = T_world_cam[:3, :3], T_world_cam[:3, 3]
        m = _BAND_PX + 2  # margin: band radius + bulge of distorted straight edges between vertices
        for obj in self.scene.dynamic:
            v = obj.mesh.transformed(obj.pose(t_s)).vertices
            pc = (v - o) @ R
            if (pc[:, 2] < 0.05).any():
                if (pc[:, 2] > 0.05).any():
                    return None  # straddles the camera plane: its image is unbounded
                continue  # entirely behind the camera
            uv = self.calibration.project(pc)
            if not np.isfinite(uv).all():
                return None
            x0, y0 = np.floor(uv.min(axis=0)).astype(int) - m
            x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + m
            if x1 < 0 or y1 < 0 or x0 >= w or y0 >= h:
                continue
            out[max(y0, 0) : min(y1, h - 1) + 1, max(x0, 0) : min(x1, w - 1) + 1] = True
        return out

    def log_image(self, out: RenderOutput, gains: np.ndarray) -> np.ndarray:
        """(H, W) float64 log intensity for the given light-group gains."""
        lin = np.tensordot(np.asarray(gains, np.float64), out.group_images.astype(np.float64), axes=1)
        return np.log(lin + self.config.log_eps)
