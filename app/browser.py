"""The recordings browser: what lives under the ``--data`` roots, and nothing outside them.

Files are found by name (recordings: ``*.h5``/``*.hdf5``/``*.bag``, ECD folders
with ``events.txt``; contour maps ``*_map.ply``; raw clouds ``*_cloud.ply``) and
probed cheaply; a file that cannot be read is still listed, with the reason,
so one corrupt file never stops the server.
"""

from __future__ import annotations

import enum
import os
from dataclasses import dataclass
from pathlib import Path

from evpose.core.contour_map import ContourMap
from evpose.core.recording import Recording
from evpose.errors import EvposeError, InputError

RECORDING_SUFFIXES = (".h5", ".hdf5", ".bag")


class EntryKind(str, enum.Enum):
    """What a file in a data root is."""

    RECORDING = "recording"
    MAP = "map"
    CLOUD = "cloud"


@dataclass(frozen=True)
class DataEntry:
    """One file or folder found under a data root."""

    kind: EntryKind
    path: Path
    """Resolved absolute path."""
    label: str
    """Path relative to its root, prefixed with the root's name (what the dropdown shows)."""
    error: str | None = None
    """Why the entry cannot be read, or None if it probed fine."""

    @property
    def display(self) -> str:
        return f"{self.label} (unreadable: {self.error})" if self.error else self.label


class DataRoots:
    """The folders the viewer may read from; every path the UI asks for is checked against them."""

    def __init__(self, roots: list[str | Path]):
        self.roots = [Path(r).expanduser().resolve() for r in roots]

    def check(self, path: str | Path) -> Path:
        """The resolved path if it lies inside one of the roots (symlinks followed); else InputError."""
        p = Path(path).expanduser()
        resolved = p.resolve() if p.is_absolute() else None
        if resolved is None:
            for root in self.roots:
                cand = (root / p).resolve()
                if cand.exists():
                    resolved = cand
                    break
            else:
                resolved = p.resolve()
        for root in self.roots:
            if resolved == root or root in resolved.parents:
                return resolved
        raise InputError(path, "refused: outside the data directories " + ", ".join(str(r) for r in self.roots))

    def scan(self) -> list[DataEntry]:
        """All recordings, maps and clouds under the roots, sorted by label; unreadable ones carry the reason."""
        out: list[DataEntry] = []
        for root in self.roots:
            if not root.is_dir():
                continue
            for dirpath, dirnames, filenames in os.walk(root, followlinks=False):
                dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
                here = Path(dirpath)
                if "events.txt" in filenames:
                    out.append(self._entry(EntryKind.RECORDING, here, root))
                for name in sorted(filenames):
                    if name.startswith("."):
                        continue
                    low = name.lower()
                    kind = None
                    if low.endswith(RECORDING_SUFFIXES):
                        kind = EntryKind.RECORDING
                    elif low.endswith("_cloud.ply"):
                        kind = EntryKind.CLOUD
                    elif low.endswith(".ply"):
                        kind = EntryKind.MAP
                    if kind is not None:
                        out.append(self._entry(kind, here / name, root))
        return sorted(out, key=lambda e: (e.kind.value, e.label))

    def _entry(self, kind: EntryKind, path: Path, root: Path) -> DataEntry:
        try:
            resolved = self.check(path)
        except InputError as exc:
            # A symlink leading out of the roots is listed but never opened.
            return DataEntry(kind, path, f"{root.name}/{path.relative_to(root)}", exc.problem)
        return DataEntry(kind, resolved, f"{root.name}/{path.relative_to(root)}", probe(kind, resolved))


def scan_note(entries: list[DataEntry], roots: DataRoots, cache_note: str = "") -> str:
    """What a scan found, in words: counts, missing roots, why the disk cache is off, and every unreadable file with its reason."""
    recs = [e for e in entries if e.kind == EntryKind.RECORDING]
    maps = [e for e in entries if e.kind == EntryKind.MAP]
    bad = [e for e in entries if e.error]
    note = f"{len(recs)} recordings, {len(maps)} maps under " + ", ".join(f"`{r}`" for r in roots.roots)
    missing = [r for r in roots.roots if not r.is_dir()]
    if missing:
        note += "\n\n" + "; ".join(f"`{r}` does not exist" for r in missing)
    if cache_note:
        note += f"\n\n_{cache_note}_"
    if bad:
        note += "\n\n**Unreadable:**\n" + "\n".join(f"- `{e.label}`: {e.error}" for e in bad)
    return note


def probe(kind: EntryKind, path: Path) -> str | None:
    """Cheap readability check: the reason a file cannot be read, or None.

    Headers only, never the events: an evpose h5's event count is its dataset's shape; an ECD folder's events.txt
    is checked by its first line (and calib.txt, evpose.json, which are a few bytes). Files that would be refused
    only when opened (no events, a text folder whose events cannot be parsed) were listed as normal.
    """
    try:
        if kind == EntryKind.RECORDING and path.suffix.lower() in (".h5", ".hdf5"):
            from evpose.io.h5 import H5RecordingReader
            from evpose.io.open import SourceFormat, detect_format

            try:
                if detect_format(path) is SourceFormat.EVENT_H5 and _opens_as_hdf5(path):
                    return None  # another event h5 layout (TUM-VIE, VECtor, DSEC): checked when opened
            except EvposeError:
                pass  # not HDF5 at all, or truncated: the reader below says so
            with H5RecordingReader(path) as reader:
                if reader.n_events == 0:
                    return "contains no events"
        elif kind == EntryKind.RECORDING and path.is_dir():
            return _probe_ecd(path)
        elif kind in (EntryKind.MAP, EntryKind.CLOUD):
            with open(path, "rb") as fh:
                head = fh.read(256)
            if not head.startswith(b"ply"):
                return "not a PLY file (missing 'ply' magic)"
            if b"element vertex" not in head and b"end_header" not in head:
                return "PLY header has no vertex element"
        elif path.is_file() and path.stat().st_size == 0:
            return "empty file"
    except EvposeError as exc:
        return getattr(exc, "problem", str(exc))
    except (OSError, ValueError, KeyError) as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def _opens_as_hdf5(path: Path) -> bool:
    """Whether h5py opens ``path`` (a truncated file keeps its HDF5 signature but does not)."""
    import h5py

    try:
        with h5py.File(path, "r"):
            return True
    except (OSError, ValueError):
        return False


def _probe_ecd(folder: Path) -> str | None:
    """What is wrong with an ECD folder that can be seen without reading its events (None: nothing)."""
    from evpose.io.ecd import CALIB_FILE, EVENTS_FILE, read_ecd_calib, read_ecd_sidecar

    events = folder / EVENTS_FILE
    if not events.is_file():  # a dangling link, or a folder named events.txt
        return f"{EVENTS_FILE}: no such file"
    with open(events, "rb") as fh:
        head = fh.read(4096)
        whole = not fh.read(1)
    lines = head.split(b"\n")
    if not whole:
        lines = lines[:-1]  # cut mid-line
    # The reader skips blank lines and '#' comments; the first other line must be 't x y p'.
    for number, line in enumerate(lines, 1):
        words = line.split()
        if not words or words[0].startswith(b"#"):
            continue
        try:
            [float(w) for w in words]
        except ValueError:
            words = []
        if len(words) != 4:
            text = line[:80].decode("utf-8", "replace").strip()
            return f"{EVENTS_FILE}: line {number}: expected 4 numbers 't x y p', got {text!r}"
        break
    else:
        if whole:
            return f"{EVENTS_FILE}: contains no events"
    try:
        read_ecd_sidecar(folder)
        if (folder / CALIB_FILE).is_file():
            read_ecd_calib(folder / CALIB_FILE)
    except InputError as exc:  # which of the folder's files
        return f"{Path(exc.path).name}: {exc.problem}" if exc.path else exc.problem
    return None


def load_recording(path: Path) -> Recording:
    """Read a whole recording with the project's reader (``evpose.io.open`` when present)."""
    try:
        from evpose.io.open import open_recording
    except ModuleNotFoundError:
        open_recording = None
    if open_recording is not None:
        rec = open_recording(path)
        rec = rec if isinstance(rec, Recording) else rec.to_recording()
    elif path.suffix.lower() in (".h5", ".hdf5"):
        from evpose.io.h5 import read_recording_h5

        rec = read_recording_h5(path)
    else:
        raise InputError(path, "no reader for this format in this build")
    if len(rec.events) == 0:
        # Refused as `evpose info` does: opened, it was a 0 s recording of black panels whose only word on why
        # was in the parameters panel, and the warm-up called it "Tracking cannot start".
        raise InputError(path, "contains no events")
    return rec


def load_map(path: Path) -> ContourMap:
    from evpose.io.map_ply import read_contour_map

    return read_contour_map(path)


def load_cloud(path: Path):
    """Raw cloud positions (N, 3) and colours (N, 3) uint8 or None."""
    import numpy as np

    from evpose.io.map_ply import read_point_cloud

    pts, attrs = read_point_cloud(path)
    colors = None
    if "colors" in attrs:
        colors = np.clip(attrs["colors"] * 255.0, 0, 255).astype(np.uint8)
    return pts, colors


def guess_map_for(recording_entry: DataEntry, maps: list[DataEntry], metadata: dict | None = None) -> DataEntry | None:
    """The contour map that belongs to a recording: same scene name in metadata or as a file-name prefix."""
    usable = [m for m in maps if m.error is None and m.kind == EntryKind.MAP]
    keys = []
    if metadata:
        for k in ("scene", "map", "scenario"):
            if isinstance(metadata.get(k), str):
                keys.append(Path(metadata[k]).stem.lower())
    stem = recording_entry.path.stem.lower()
    keys.append(stem)
    for key in keys:
        for m in usable:
            mstem = m.path.stem.lower().removesuffix("_map")
            if key == mstem or key.startswith(mstem) or mstem.startswith(key):
                return m
    return None
