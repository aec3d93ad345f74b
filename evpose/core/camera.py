"""Camera calibration: pinhole intrinsics with radial-tangential or equidistant (Kannala-Brandt) distortion.

Conventions: OpenCV camera frame (x right, y down, z forward); pixel centres at
integer coordinates. ``project`` maps camera-frame points to *distorted* pixels
(what the sensor sees); ``undistort_pixels`` maps sensor pixels to the ideal
pinhole image with the same ``K``, which is where the tracker works.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from functools import cached_property

import numba as nb
import numpy as np

from evpose.errors import InputError

_NEWTON_ITERS = 40


class DistortionModel(str, enum.Enum):
    """Lens model of a calibration; values are the names used in files."""

    NONE = "none"
    RADTAN = "radtan"
    """Brown-Conrady: coefficients k1 k2 p1 p2 k3 (OpenCV order)."""
    EQUIDISTANT = "equidistant"
    """Kannala-Brandt / fisheye: coefficients k1 k2 k3 k4 on theta."""


_N_COEFFS = {DistortionModel.NONE: 0, DistortionModel.RADTAN: 5, DistortionModel.EQUIDISTANT: 4}


@nb.njit(cache=True)
def _radtan_distort(a, b, k1, k2, p1, p2, k3):
    r2 = a * a + b * b
    rad = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    ad = a * rad + 2.0 * p1 * a * b + p2 * (r2 + 2.0 * a * a)
    bd = b * rad + p1 * (r2 + 2.0 * b * b) + 2.0 * p2 * a * b
    return ad, bd


@nb.njit(cache=True)
def _radtan_undistort_many(ad, bd, k1, k2, p1, p2, k3, iters):
    n = ad.shape[0]
    a_out = np.empty(n)
    b_out = np.empty(n)
    for i in range(n):
        a = ad[i]
        b = bd[i]
        for _ in range(iters):
            r2 = a * a + b * b
            rad = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
            drad = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)
            fa = a * rad + 2.0 * p1 * a * b + p2 * (r2 + 2.0 * a * a) - ad[i]
            fb = b * rad + p1 * (r2 + 2.0 * b * b) + 2.0 * p2 * a * b - bd[i]
            jaa = rad + 2.0 * a * a * drad + 2.0 * p1 * b + 6.0 * p2 * a
            jab = 2.0 * a * b * drad + 2.0 * p1 * a + 2.0 * p2 * b
            jba = 2.0 * a * b * drad + 2.0 * p1 * a + 2.0 * p2 * b
            jbb = rad + 2.0 * b * b * drad + 6.0 * p1 * b + 2.0 * p2 * a
            det = jaa * jbb - jab * jba
            if det == 0.0:
                break
            da = (jbb * fa - jab * fb) / det
            db = (-jba * fa + jaa * fb) / det
            a -= da
            b -= db
            if abs(da) + abs(db) < 1e-15:
                break
        a_out[i] = a
        b_out[i] = b
    return a_out, b_out


@nb.njit(cache=True)
def _kb_theta_from_distorted(thd, k1, k2, k3, k4, iters):
    n = thd.shape[0]
    out = np.empty(n)
    for i in range(n):
        th = thd[i]
        for _ in range(iters):
            t2 = th * th
            f = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - thd[i]
            df = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + 9.0 * k4 * t2)))
            if df == 0.0:
                break
            step = f / df
            th -= step
            if abs(step) < 1e-16:
                break
        out[i] = th
    return out


MAX_SENSOR_PX = 65536
"""Largest sensor width or height, pixels: event columns are uint16 (the same bound as ``--width/--height``)."""
_FOCAL_PER_PX = (1e-3, 1e3)
"""Plausible focal lengths, in sensor widths (heights for fy)."""
MAX_EXTRINSIC_M = 100.0
"""Largest camera-IMU translation accepted in ``T_cam_imu``, metres."""
MAX_TIME_OFFSET_US = 10**17
"""Largest camera-IMU clock offset accepted, microseconds (3170 years: an IMU on Unix time beside a camera counting from
0 is 1.7e15). A kalibr ``timeshift_cam_imu`` of 1e300 s passed, and event times plus it overflowed int64 later."""

_LENS_ANGLE_RATIO = (0.1, 10.0)
"""Plausible ratios of the off-axis angle a lens model gives the sensor's farthest pixels to the pinhole's angle."""

_RIGID_TOL = 5e-3
"""Largest deviation of ``R^T R`` from the identity (and of the bottom row from 0 0 0 1) accepted in ``T_cam_imu``: loose
enough for rotations printed with 3-4 decimals, tight enough to refuse a scaled or sheared matrix."""


def _whole(value, name: str) -> int:
    """An integer field of a calibration file: 346.5 pixels or 12.5 us were truncated silently."""
    number = float(value)
    if not number.is_integer():
        raise InputError(None, f"calibration's {name} {value!r} is not a whole number")
    return int(number)


def _check_rigid(T: np.ndarray) -> None:
    """Refuse a ``T_cam_imu`` that is not a rigid transform: the fusion would rotate the IMU by a non-rotation and the
    tracker then blamed the map ("no update registered against this map")."""
    R = T[:3, :3]
    if np.abs(T[3] - (0.0, 0.0, 0.0, 1.0)).max() > _RIGID_TOL:
        raise InputError(None, f"calibration's T_cam_imu bottom row is {T[3].tolist()}, expected [0, 0, 0, 1]")
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > _RIGID_TOL or np.linalg.det(R) <= 0:
        raise InputError(None, f"calibration's T_cam_imu rotation is not a rotation matrix (|R^T R - I| = {err:.3g}, det {np.linalg.det(R):.3g})")


@dataclass(frozen=True)
class CameraCalibration:
    """Intrinsics, distortion and the camera-IMU extrinsic of one event camera."""

    width: int
    """Sensor width in pixels."""
    height: int
    """Sensor height in pixels."""
    fx: float
    """Focal length along x, pixels."""
    fy: float
    """Focal length along y, pixels."""
    cx: float
    """Principal point column, pixels."""
    cy: float
    """Principal point row, pixels."""
    model: DistortionModel = DistortionModel.NONE
    """Lens distortion model."""
    dist: tuple[float, ...] = ()
    """Distortion coefficients in the model's order (radtan: k1 k2 p1 p2 k3; equidistant: k1..k4)."""
    T_cam_imu: np.ndarray = field(default_factory=lambda: np.eye(4))
    """Rigid transform mapping IMU-frame points into the camera frame (4x4)."""
    time_offset_us: int = 0
    """Clock offset: ``t_imu = t_cam + time_offset_us``."""

    def __post_init__(self):
        object.__setattr__(self, "model", DistortionModel(self.model))
        dist = tuple(float(d) for d in self.dist)
        if self.model is DistortionModel.NONE and dist and not any(dist):
            dist = ()
        if len(dist) != _N_COEFFS[self.model]:
            raise InputError(None, f"{self.model.value} distortion needs {_N_COEFFS[self.model]} coefficients, got {len(dist)}")
        object.__setattr__(self, "dist", dist)
        T = np.asarray(self.T_cam_imu, dtype=np.float64).reshape(4, 4)
        object.__setattr__(self, "T_cam_imu", T)
        vals = (self.fx, self.fy, self.cx, self.cy) + dist
        if not all(np.isfinite(v) for v in vals) or not np.isfinite(T).all():
            raise InputError(None, "calibration has NaN or infinite values")
        if self.width <= 0 or self.height <= 0 or self.fx <= 0 or self.fy <= 0:
            raise InputError(None, f"calibration needs positive size and focal lengths, got {self.width}x{self.height}, fx={self.fx}, fy={self.fy}")
        # Pixel columns are uint16 (a width of 1e9 allocated terabytes for the first time surface, with a traceback).
        if self.width > MAX_SENSOR_PX or self.height > MAX_SENSOR_PX:
            raise InputError(None, f"calibration's sensor size {self.width}x{self.height} is beyond {MAX_SENSOR_PX} pixels")
        # Focal lengths outside 1e-3..1e3 sensor widths are fields of view beyond 179.9 deg or under 0.06 deg: garbage
        # or another unit (fx=1e-300 overflowed the projection with a traceback).
        for name, f, size in (("fx", self.fx, self.width), ("fy", self.fy, self.height)):
            if not _FOCAL_PER_PX[0] * size <= f <= _FOCAL_PER_PX[1] * size:
                raise InputError(None, f"calibration's {name}={f:g} px is not a focal length for a {size} px sensor side"
                                       f" (expected {_FOCAL_PER_PX[0] * size:g}..{_FOCAL_PER_PX[1] * size:g} px)")
        # Camera and IMU sit on one rig: a translation beyond MAX_EXTRINSIC_M is garbage (1e300 printed numpy's overflow
        # warnings and the tracker then blamed the map).
        if np.abs(T[:3, 3]).max() > MAX_EXTRINSIC_M:
            raise InputError(None, f"calibration's T_cam_imu translation {T[:3, 3].tolist()} m is beyond {MAX_EXTRINSIC_M:g} m (not metres?)")
        # A principal point off the sensor projects nothing onto it: the tracker then blamed the map ("no map point in view").
        if not (0.0 <= self.cx <= self.width and 0.0 <= self.cy <= self.height):
            raise InputError(None, f"calibration's principal point ({self.cx:g}, {self.cy:g}) px lies outside the {self.width}x{self.height} sensor")
        try:
            offset_ok = abs(self.time_offset_us) <= MAX_TIME_OFFSET_US  # False for NaN
        except TypeError:
            offset_ok = False
        if not offset_ok:
            text = repr(self.time_offset_us)
            raise InputError(None, f"calibration's time_offset_us {text if len(text) <= 24 else text[:21] + '...'} is not a number of"
                                   f" microseconds within +-{MAX_TIME_OFFSET_US:.0e}")
        _check_rigid(T)
        self._check_invertible()

    def _check_invertible(self) -> None:
        """Refuse distortion coefficients that fold the image or shrink / widen it beyond any lens: along rays from the
        principal point, within the largest disc around it that the sensor holds, the angle from the optical axis must
        grow, the undistortion must distort back to its pixel, and the disc's edge must lie within 0.1-10x the angle a
        pinhole with the same K gives it. Coefficients from another lens or unit (k1 = 1e9) passed, and the tracker then
        blamed the map ("no update registered against this map"). The corners beyond the disc are not checked: a
        calibration fitted on a wide lens may fold there, where its target rarely reached, and still serve the rest."""
        if self.model is DistortionModel.NONE:
            return
        pc = np.array([self.cx, self.cy])
        radius = min(self.cx, self.width - 1.0 - self.cx, self.cy, self.height - 1.0 - self.cy)
        if radius < 1.0:
            return
        directions = np.exp(1j * np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False))
        steps = np.linspace(0.0, radius, 65)[1:]
        offsets = directions[:, None] * steps[None, :]
        uv = pc + np.stack([offsets.real.ravel(), offsets.imag.ravel()], axis=1)
        with np.errstate(all="ignore"):
            rays = self.unproject(uv)
            back = self.project(rays)
            angle = np.arccos(np.clip(rays[:, 2], -1.0, 1.0)).reshape(len(directions), -1)
            off = np.hypot(*(back - uv).T)
            md = (uv - pc) / (self.fx, self.fy)
            pinhole = np.arctan(np.hypot(md[:, 0], md[:, 1])).reshape(len(directions), -1)[:, -1]
            ratio = angle[:, -1] / pinhole
        coeffs = " ".join(f"{d:g}" for d in self.dist)
        folds = not np.isfinite(angle).all() or (np.diff(angle, axis=1) < -1e-9).any()
        worst = float(np.nanmax(off)) if np.isfinite(off).any() else np.inf
        if folds or not np.isfinite(off).all() or worst > 0.01:
            raise InputError(None, f"calibration's {self.model.value} distortion ({coeffs}) does not invert within "
                                   f"{radius:.0f} px of the principal point (a pixel comes back {worst:.3g} px off"
                                   f"{' and the image folds' if folds else ''}): coefficients of another lens or unit?")
        if not (_LENS_ANGLE_RATIO[0] <= ratio.min() and ratio.max() <= _LENS_ANGLE_RATIO[1]):
            raise InputError(None, f"calibration's {self.model.value} distortion ({coeffs}) puts a pixel {radius:.0f} px "
                                   f"from the principal point {np.degrees(angle[:, -1].max()):.3g} deg off the axis, "
                                   f"against {np.degrees(pinhole.max()):.3g} deg without it: coefficients of another lens or unit?")

    # ------------------------------------------------------------------ basics
    @property
    def K(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def resolution(self) -> tuple[int, int]:
        return self.width, self.height

    def without_distortion(self) -> "CameraCalibration":
        """The ideal pinhole camera with the same ``K``, size and extrinsic."""
        return CameraCalibration(self.width, self.height, self.fx, self.fy, self.cx, self.cy, DistortionModel.NONE, (), self.T_cam_imu, self.time_offset_us)

    # --------------------------------------------------------------- distortion
    def distort_normalized(self, ab: np.ndarray) -> np.ndarray:
        """Ideal normalized coordinates ``(X/Z, Y/Z)`` -> distorted normalized coordinates (N, 2)."""
        ab = np.asarray(ab, dtype=np.float64).reshape(-1, 2)
        a, b = ab[:, 0], ab[:, 1]
        if self.model is DistortionModel.NONE:
            return ab.copy()
        if self.model is DistortionModel.RADTAN:
            ad, bd = _radtan_distort(a, b, *self.dist)
            return np.stack([ad, bd], axis=1)
        r = np.hypot(a, b)
        th = np.arctan(r)
        thd = self._kb_poly(th)
        scale = np.where(r > 1e-12, thd / np.where(r > 1e-12, r, 1.0), 1.0)
        return ab * scale[:, None]

    def undistort_normalized(self, ab_d: np.ndarray) -> np.ndarray:
        """Distorted normalized coordinates -> ideal ``(X/Z, Y/Z)`` (Newton iterations, inverse to ~1e-12)."""
        ab_d = np.asarray(ab_d, dtype=np.float64).reshape(-1, 2)
        if self.model is DistortionModel.NONE:
            return ab_d.copy()
        ad = np.ascontiguousarray(ab_d[:, 0])
        bd = np.ascontiguousarray(ab_d[:, 1])
        if self.model is DistortionModel.RADTAN:
            a, b = _radtan_undistort_many(ad, bd, *self.dist, _NEWTON_ITERS)
            return np.stack([a, b], axis=1)
        thd = np.hypot(ad, bd)
        th = _kb_theta_from_distorted(thd, *self.dist, _NEWTON_ITERS)
        scale = np.where(thd > 1e-12, np.tan(th) / np.where(thd > 1e-12, thd, 1.0), 1.0)
        return ab_d * scale[:, None]

    def _kb_poly(self, th: np.ndarray) -> np.ndarray:
        k1, k2, k3, k4 = self.dist
        t2 = th * th
        return th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))

    # ------------------------------------------------------- project/unproject
    def project(self, points_cam: np.ndarray) -> np.ndarray:
        """Camera-frame points (N, 3) -> sensor pixels (N, 2); NaN for points the model cannot image."""
        P = np.asarray(points_cam, dtype=np.float64).reshape(-1, 3)
        X, Y, Z = P[:, 0], P[:, 1], P[:, 2]
        if self.model is DistortionModel.EQUIDISTANT:
            r = np.hypot(X, Y)
            th = np.arctan2(r, Z)
            thd = self._kb_poly(th)
            safe_r = np.where(r > 1e-12, r, 1.0)
            mx = np.where(r > 1e-12, thd * X / safe_r, X / np.where(Z > 0, Z, np.nan))
            my = np.where(r > 1e-12, thd * Y / safe_r, Y / np.where(Z > 0, Z, np.nan))
            m = np.stack([mx, my], axis=1)
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                zs = np.where(Z > 1e-12, Z, np.nan)
                m = self.distort_normalized(np.stack([X / zs, Y / zs], axis=1))
        return np.stack([self.fx * m[:, 0] + self.cx, self.fy * m[:, 1] + self.cy], axis=1)

    def unproject(self, pixels: np.ndarray) -> np.ndarray:
        """Sensor pixels (N, 2) -> unit bearing vectors (N, 3) in the camera frame."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        md = np.stack([(uv[:, 0] - self.cx) / self.fx, (uv[:, 1] - self.cy) / self.fy], axis=1)
        if self.model is DistortionModel.EQUIDISTANT:
            thd = np.hypot(md[:, 0], md[:, 1])
            th = _kb_theta_from_distorted(np.ascontiguousarray(thd), *self.dist, _NEWTON_ITERS)
            s = np.where(thd > 1e-12, np.sin(th) / np.where(thd > 1e-12, thd, 1.0), 1.0)
            return np.stack([md[:, 0] * s, md[:, 1] * s, np.cos(th)], axis=1)
        ab = self.undistort_normalized(md)
        rays = np.concatenate([ab, np.ones((ab.shape[0], 1))], axis=1)
        return rays / np.linalg.norm(rays, axis=1, keepdims=True)

    def undistort_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Sensor pixels -> pixels of the ideal pinhole camera with the same ``K`` (N, 2)."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        if self.model is DistortionModel.NONE:
            return uv.copy()
        md = np.stack([(uv[:, 0] - self.cx) / self.fx, (uv[:, 1] - self.cy) / self.fy], axis=1)
        ab = self.undistort_normalized(md)
        return np.stack([self.fx * ab[:, 0] + self.cx, self.fy * ab[:, 1] + self.cy], axis=1)

    @cached_property
    def undistortion_table(self) -> np.ndarray:
        """(H, W, 2) float32: ideal pinhole coordinates of every sensor pixel, for per-event lookup."""
        ys, xs = np.mgrid[0 : self.height, 0 : self.width]
        uv = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
        return self.undistort_pixels(uv).reshape(self.height, self.width, 2).astype(np.float32)

    # ---------------------------------------------------------------- files
    def to_dict(self) -> dict:
        return {
            "width": int(self.width),
            "height": int(self.height),
            "fx": float(self.fx),
            "fy": float(self.fy),
            "cx": float(self.cx),
            "cy": float(self.cy),
            "model": self.model.value,
            "dist": [float(d) for d in self.dist],
            "T_cam_imu": self.T_cam_imu.tolist(),
            "time_offset_us": int(self.time_offset_us),
        }

    @classmethod
    def from_dict(cls, d: dict, source: str | None = None) -> "CameraCalibration":
        try:
            return cls(
                width=_whole(d["width"], "width"),
                height=_whole(d["height"], "height"),
                fx=float(d["fx"]),
                fy=float(d["fy"]),
                cx=float(d["cx"]),
                cy=float(d["cy"]),
                model=DistortionModel(d.get("model", "none")),
                dist=tuple(d.get("dist", ())),
                T_cam_imu=np.asarray(d.get("T_cam_imu", np.eye(4)), dtype=np.float64),
                time_offset_us=_whole(d.get("time_offset_us", 0), "time_offset_us"),
            )
        except KeyError as exc:
            raise InputError(source, f"calibration is missing the field {exc.args[0]!r}") from None
        except InputError as exc:
            raise InputError(source, exc.problem) from None
        except (TypeError, ValueError, OverflowError) as exc:  # OverflowError: a JSON integer of 400 digits
            raise InputError(source, f"calibration is malformed ({exc})") from None
