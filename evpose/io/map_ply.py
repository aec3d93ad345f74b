"""Contour maps as PLY files with named per-vertex properties.

Schema (binary little-endian, one ``vertex`` element):

=================  =======  ===================================================
property           type     meaning
=================  =======  ===================================================
x y z              double   position in the world, metres
enx eny enz        float    in-plane outward edge normal (unit, 0 if unknown)
nx ny nz           float    plane normal (unit, 0 if unknown)
region             int      region id (-1 none)
curvature          float    surface variation at the point
brightness_sign    char     +1 brighter along the edge normal, -1 darker, 0 unknown
=================  =======  ===================================================

Plain point clouds (``.ply``/``.pcd`` without these properties) are read with
open3d and become maps with unknown attributes.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from evpose.core.contour_map import ContourMap
from evpose.core.trajectory import MAX_COORDINATE_M  # noqa: F401 - the bound shared with trajectories
from evpose.errors import InputError
from evpose.io.atomic import atomic_path
from evpose.io.paths import not_a_file

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}

_SCHEMA = [
    ("x", "f8"), ("y", "f8"), ("z", "f8"),
    ("enx", "f4"), ("eny", "f4"), ("enz", "f4"),
    ("nx", "f4"), ("ny", "f4"), ("nz", "f4"),
    ("region", "i4"), ("curvature", "f4"), ("brightness_sign", "i1"),
]
_NAMES = {"f8": "double", "f4": "float", "i4": "int", "i1": "char"}


class MapFileError(InputError):
    """A map file that cannot be read as a point cloud or contour map."""


def write_contour_map(path: str | Path, cmap: ContourMap, comment: str = "evpose contour map") -> None:
    """Write ``cmap`` atomically as binary PLY with the schema above."""
    n = len(cmap)
    rec = np.empty(n, dtype=[(name, "<" + t) for name, t in _SCHEMA])
    rec["x"], rec["y"], rec["z"] = cmap.points.T
    rec["enx"], rec["eny"], rec["enz"] = cmap.edge_normal.T
    rec["nx"], rec["ny"], rec["nz"] = cmap.plane_normal.T
    rec["region"] = cmap.region_id
    rec["curvature"] = cmap.curvature
    rec["brightness_sign"] = cmap.brightness_sign
    header = ["ply", "format binary_little_endian 1.0", f"comment {comment}", f"element vertex {n}"]
    header += [f"property {_NAMES[t]} {name}" for name, t in _SCHEMA]
    header.append("end_header")
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(("\n".join(header) + "\n").encode("ascii"))
            fh.write(rec.tobytes())


def _parse_header(fh, path: Path):
    first = fh.readline()
    if first.strip() != b"ply":
        return None
    fmt = None
    elements: list[tuple[str, int, list[tuple[str, str]]]] = []
    lineno = 1
    while True:
        line = fh.readline()
        lineno += 1
        if not line:
            raise MapFileError(path, "PLY header has no end_header")
        words = line.decode("ascii", "replace").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise MapFileError(path, f"expected 'element NAME COUNT' with a non-negative count, got {line.decode('ascii', 'replace').strip()!r}", f"header line {lineno}")
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if not elements:
                raise MapFileError(path, "PLY property before any element")
            if words[1] == "list":
                elements[-1][2].append((words[-1], "list"))
            elif words[1] in _PLY_TYPES:
                elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
            else:
                raise MapFileError(path, f"unknown PLY property type {words[1]!r}")
        elif words[0] == "end_header":
            if fmt is None:
                raise MapFileError(path, "PLY header has no 'format' line")
            return fmt, elements


def _read_vertices(path: Path) -> np.ndarray | None:
    """Structured vertex array for simple PLY files, None where open3d must take over."""
    with open(path, "rb") as fh:
        parsed = _parse_header(fh, path)
        if parsed is None:
            return None
        fmt, elements = parsed
        if not elements or elements[0][0] != "vertex" or any(t == "list" for _, t in elements[0][2]):
            return None
        _, n, props = elements[0]
        data_bytes = path.stat().st_size - fh.tell()
        # Every vertex takes at least one byte per property (a digit and a separator in ASCII): a count beyond that is a
        # damaged header, refused before allocating an array for it.
        if n * len(props) > data_bytes:
            raise MapFileError(path, f"file is truncated: header promises {n} vertices, the data after the header has only {data_bytes} bytes")
        if fmt in ("binary_little_endian", "binary_big_endian"):
            # Big-endian maps went to open3d, which kept the points and dropped every attribute (edge normals...) silently.
            order = "<" if fmt == "binary_little_endian" else ">"
            dtype = np.dtype([(name, order + t) for name, t in props])
            raw = fh.read(n * dtype.itemsize)
            if len(raw) < n * dtype.itemsize:
                raise MapFileError(path, f"file is truncated: header promises {n} vertices, data holds {len(raw) // dtype.itemsize}")
            return np.frombuffer(raw, dtype=dtype, count=n).astype(dtype.newbyteorder("="))
        if fmt == "ascii":
            dtype = np.dtype([(name, t) for name, t in props])
            out = np.empty(n, dtype=dtype)
            for i in range(n):
                line = fh.readline()
                vals = line.split()
                if len(vals) != len(props):
                    raise MapFileError(path, f"expected {len(props)} values, got {len(vals)}", f"vertex {i}")
                try:
                    out[i] = tuple(float(v) for v in vals)
                except ValueError:
                    raise MapFileError(path, "not a number", f"vertex {i}") from None
            return out
        raise MapFileError(path, f"unknown PLY format {fmt!r} (ascii, binary_little_endian or binary_big_endian)")




def _check_points(points: np.ndarray, path: Path) -> None:
    if points.shape[0] == 0:
        raise MapFileError(path, "point cloud is empty")
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise MapFileError(path, "NaN or infinite coordinate", f"point {int(bad[0])}")
    bad = np.flatnonzero(np.abs(points).max(axis=1) > MAX_COORDINATE_M)
    if bad.size:
        raise MapFileError(path, f"coordinate {points[bad[0]].tolist()} is beyond {MAX_COORDINATE_M:g} m (not metres?)", f"point {int(bad[0])}")


MAX_SHARED_POSITION = 1000
"""Most map points that may share one position. A contour map holds each position once (the landing and indoor maps:
no two points alike); a map collapsed onto one point (a scale-0 export, a cloud whose missing returns were written
as 0 0 0) made the tracker's KD-tree queries quadratic in the points stacked there: 97 k identical points hung
``track``, ``refine-map`` and ``app --prepare`` in ``wall_occlusion`` for hours; 10 k cost ~1 s per query pass, 1 k
nothing measurable (session 30, /tmp/s30/fuzz30/)."""


def _check_distinct(points: np.ndarray, path: Path) -> None:
    """Refuse a contour map with more than :data:`MAX_SHARED_POSITION` points at one position (~0.1 s on 97 k points)."""
    if points.shape[0] <= MAX_SHARED_POSITION:
        return
    _, first, counts = np.unique(points, axis=0, return_index=True, return_counts=True)
    k = int(np.argmax(counts))
    if counts[k] > MAX_SHARED_POSITION:
        raise MapFileError(path, f"{int(counts[k])} of the {points.shape[0]} points share the position {points[first[k]].tolist()}"
                           " (a collapsed or damaged map; a contour map holds each position once)", f"point {int(first[k])}")


_UNIT_TOL = 1e-2
"""How far from 1 the length of a known (non-zero) normal may be."""


def _check_attributes(attrs: dict[str, np.ndarray], path: Path) -> None:
    """The schema's per-point attributes hold what the tracker assumes: finite unit normals (or 0 = unknown), finite
    curvature, brightness signs -1/0/+1. A NaN normal ended in a KD-tree traceback; a sign of 7 was used as a weight."""
    for key, label in (("edge_normal", "edge normal"), ("plane_normal", "plane normal")):
        if key not in attrs:
            continue
        n = np.asarray(attrs[key], dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(n).all(axis=1))
        if bad.size:
            raise MapFileError(path, f"NaN or infinite {label}", f"point {int(bad[0])}")
        length = np.linalg.norm(n, axis=1)
        bad = np.flatnonzero((length != 0) & (np.abs(length - 1.0) > _UNIT_TOL))
        if bad.size:
            raise MapFileError(path, f"{label} has length {length[bad[0]]:.4g} (a unit vector, or 0 for unknown)", f"point {int(bad[0])}")
    if "curvature" in attrs:
        bad = np.flatnonzero(~np.isfinite(attrs["curvature"]))
        if bad.size:
            raise MapFileError(path, "NaN or infinite curvature", f"point {int(bad[0])}")
    if "brightness_sign" in attrs:
        bad = np.flatnonzero(~np.isin(attrs["brightness_sign"], (-1, 0, 1)))
        if bad.size:
            raise MapFileError(path, f"brightness_sign is {int(attrs['brightness_sign'][bad[0]])} (expected -1, 0 or +1)", f"point {int(bad[0])}")


def read_contour_map(path: str | Path) -> ContourMap:
    """Read a contour map written by :func:`write_contour_map`, or any point cloud open3d reads."""
    path = Path(path)
    if not path.is_file():
        raise MapFileError(path, not_a_file(path))
    verts = None
    if path.suffix.lower() == ".ply":
        try:
            verts = _read_vertices(path)
        except (ValueError, UnicodeDecodeError) as exc:
            raise MapFileError(path, f"malformed PLY ({exc})") from None
    if verts is not None and not all(name in verts.dtype.names for name in ("x", "y", "z")):
        raise MapFileError(path, f"vertices have no x, y, z properties (they have {', '.join(verts.dtype.names)})")
    if verts is not None:
        names = set(verts.dtype.names)
        pts = np.stack([verts["x"], verts["y"], verts["z"]], axis=1).astype(np.float64)
        _check_points(pts, path)
        attrs = {}
        if {"enx", "eny", "enz"} <= names:
            attrs["edge_normal"] = np.stack([verts["enx"], verts["eny"], verts["enz"]], axis=1)
        if {"nx", "ny", "nz"} <= names:
            attrs["plane_normal"] = np.stack([verts["nx"], verts["ny"], verts["nz"]], axis=1)
        if "region" in names:
            attrs["region_id"] = verts["region"]
        if "curvature" in names:
            attrs["curvature"] = verts["curvature"]
        if "brightness_sign" in names:
            attrs["brightness_sign"] = verts["brightness_sign"]
        _check_attributes(attrs, path)
        _check_distinct(pts, path)
        return ContourMap.from_points(pts, **attrs)
    pts = read_point_cloud(path)[0]
    _check_distinct(pts, path)
    return ContourMap.from_points(pts)


def _check_ply_size(path: Path) -> None:
    """Refuse a PLY whose header promises more vertices than the file holds, before a reader allocates for them."""
    with open(path, "rb") as fh:
        try:
            parsed = _parse_header(fh, path)
        except (ValueError, UnicodeDecodeError) as exc:
            raise MapFileError(path, f"malformed PLY ({exc})") from None
        data_bytes = path.stat().st_size - fh.tell()
    if parsed is None or not parsed[1] or parsed[1][0][0] != "vertex":
        return
    fmt, ((_, n, props), *_rest) = parsed
    if any(t == "list" for _, t in props):
        return
    per_vertex = np.dtype([(name, t) for name, t in props]).itemsize if fmt.startswith("binary") else len(props)
    if n * per_vertex > data_bytes:
        raise MapFileError(path, f"file is truncated: header promises {n} vertices, the data after the header has only {data_bytes} bytes")


def _check_pcd_size(path: Path) -> None:
    """Refuse a PCD whose header promises more points than its data holds. open3d filled the missing ones with zeros
    (its legacy reader) or left them uninitialised (its tensor reader, which ``build-map`` prefers): a cut or
    miscounted scan became 900 k points at the origin, garbage coordinates or a NaN "at point 14976" of a file
    holding 30 points (session 30's fuzzing, /tmp/s30/fuzz30/)."""
    with open(path, "rb") as fh:
        fields: dict[str, list[str]] = {}
        lineno = 0
        for raw in fh:
            lineno += 1
            words = raw.decode("ascii", "replace").split()
            if not words or words[0].startswith("#"):
                continue
            fields[words[0].upper()] = words[1:]
            if words[0].upper() == "DATA" or lineno > 64:
                break
        if "DATA" not in fields:
            return  # not a PCD header open3d reads: its own reading fails on it
        try:
            n = int(fields["POINTS"][0]) if "POINTS" in fields else int(fields["WIDTH"][0]) * int(fields["HEIGHT"][0])
            sizes = [int(v) for v in fields.get("SIZE", [])]
            counts = [int(v) for v in fields.get("COUNT", ["1"] * len(sizes))]
        except (KeyError, IndexError, ValueError):
            raise MapFileError(path, "PCD header has no valid POINTS (or WIDTH and HEIGHT), SIZE or COUNT line") from None
        kind = (fields["DATA"] or ["?"])[0].lower()
        if kind == "ascii":
            have = sum(1 for line in fh if line.strip())
        elif kind == "binary":
            have = (path.stat().st_size - fh.tell()) // max(1, sum(a * b for a, b in zip(sizes, counts)))
        else:
            return  # binary_compressed: open3d checks its own sizes
    if n < 0 or have < n:
        raise MapFileError(path, f"file is truncated: header promises {n} points, the data holds {have}")


@contextlib.contextmanager
def _captured_stderr():
    """Redirect file descriptor 2 (C libraries write there directly) to a temporary file; yields a getter of its lines."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        lines: list[str] = []
        try:
            yield lambda: lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            lines.extend(tmp.read().decode("utf-8", "replace").splitlines())


def read_point_cloud(path: str | Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Raw cloud via open3d: positions (N, 3) and optional ``normals``/``colors`` (N, 3)."""
    import open3d as o3d

    path = Path(path)
    if not path.is_file():
        raise MapFileError(path, not_a_file(path))
    if path.suffix.lower() not in (".ply", ".pcd", ".xyz", ".xyzn", ".xyzrgb", ".pts"):
        raise MapFileError(path, f"not a point-cloud file (unknown suffix {path.suffix!r})")
    with open(path, "rb") as fh:
        head = fh.read(64)
    if path.suffix.lower() == ".ply" and not head.startswith(b"ply"):
        raise MapFileError(path, "not a PLY file (missing 'ply' magic)")
    if path.suffix.lower() == ".ply":
        _check_ply_size(path)
    if path.suffix.lower() == ".pcd":
        _check_pcd_size(path)
    # open3d's PLY reader (RPly) prints a damaged file's problem to stderr and returns the points read so far (a
    # truncated scan became half a map): catch what it prints and make it our one-line error instead.
    with _captured_stderr() as said:
        try:
            pcd = o3d.io.read_point_cloud(str(path))
        except MemoryError:
            raise MapFileError(path, "cannot hold the point cloud in memory (a damaged header?)") from None
    problems = [ln.strip() for ln in said() if "RPly" in ln or "Read PLY failed" in ln]
    if problems:
        raise MapFileError(path, f"malformed PLY ({problems[0]})")
    pts = np.asarray(pcd.points, dtype=np.float64)
    _check_points(pts, path)
    extra = {}
    if pcd.has_normals():
        extra["normals"] = np.asarray(pcd.normals, dtype=np.float64)
    if pcd.has_colors():
        extra["colors"] = np.asarray(pcd.colors, dtype=np.float64)
    return pts, extra
