"""Layouts: which panels are shown, where they dock, and what the 3D view shows; JSON files in ``layouts/``."""

from __future__ import annotations

import dataclasses
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from app.scene import SceneToggles
from evpose.errors import InputError

LAYOUT_DIR = Path(__file__).resolve().parent.parent / "layouts"
"""The repository's ``layouts/`` folder."""

PANELS = ("images", "plots", "teaching", "parameters")
"""The movable panels a layout places (the main control panel always stays docked left)."""

_DOCK = re.compile(r"^(left|right|float|(above|below):(images|plots|teaching|parameters))$")


@dataclass
class PanelPlacement:
    """Where one panel goes."""

    visible: bool = True
    dock: str = "right"
    """'left', 'right', 'float', or 'above:<panel>' / 'below:<panel>' to stack on another panel."""
    width: int | None = None
    """Width in CSS pixels (None = viewer default)."""


@dataclass
class Layout:
    """A named arrangement of the viewer."""

    name: str
    description: str = ""
    dark_mode: bool = False
    panels: dict[str, PanelPlacement] = field(default_factory=lambda: {p: PanelPlacement() for p in PANELS})
    scene: SceneToggles = field(default_factory=SceneToggles)

    def to_dict(self) -> dict:
        return {
            "name": self.name, "description": self.description, "dark_mode": self.dark_mode,
            "panels": {k: dataclasses.asdict(v) for k, v in self.panels.items()},
            "scene": dataclasses.asdict(self.scene),
        }

    @classmethod
    def from_dict(cls, data, source: str | None = None) -> "Layout":
        """Validate a parsed layout file; every problem names the offending key."""
        if not isinstance(data, dict):
            raise InputError(source, "a layout must be a JSON object")
        unknown = set(data) - {"name", "description", "dark_mode", "panels", "scene"}
        if unknown:
            raise InputError(source, "unknown key", sorted(unknown)[0])
        name = data.get("name")
        if not isinstance(name, str) or not name:
            raise InputError(source, "missing or empty 'name'")
        panels = {p: PanelPlacement(visible=False) for p in PANELS}
        for key, value in (data.get("panels") or {}).items():
            if key not in PANELS:
                raise InputError(source, f"unknown panel (known: {', '.join(PANELS)})", f"panels.{key}")
            if not isinstance(value, dict):
                raise InputError(source, "must be an object", f"panels.{key}")
            try:
                placement = PanelPlacement(**value)
            except TypeError as exc:
                raise InputError(source, str(exc), f"panels.{key}") from None
            if not _DOCK.match(str(placement.dock)):
                raise InputError(source, f"dock {placement.dock!r} is not left/right/float/above:<panel>/below:<panel>", f"panels.{key}")
            panels[key] = placement
        try:
            scene = SceneToggles(**(data.get("scene") or {}))
        except TypeError as exc:
            raise InputError(source, str(exc), "scene") from None
        return cls(name, str(data.get("description", "")), bool(data.get("dark_mode", False)), panels, scene)


def layout_path(name: str, directory: Path = LAYOUT_DIR) -> Path:
    """File of a layout name; names are plain words so a name can never point outside the folder."""
    if not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", name or ""):
        raise InputError(None, f"layout name {name!r} must be 1-64 letters, digits, '_' or '-'")
    return directory / f"{name}.json"


def load_layout(path: str | Path) -> Layout:
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror})") from None
    except json.JSONDecodeError as exc:
        raise InputError(path, f"not valid JSON ({exc.msg})", f"line {exc.lineno}") from None
    return Layout.from_dict(data, str(path))


def list_layouts(directory: Path = LAYOUT_DIR) -> dict[str, Layout | str]:
    """Layout name -> Layout, or the reason it cannot be loaded (a broken file never stops the viewer)."""
    out: dict[str, Layout | str] = {}
    for p in sorted(directory.glob("*.json")) if directory.is_dir() else []:
        try:
            out[p.stem] = load_layout(p)
        except InputError as exc:
            out[p.stem] = str(exc)
    return out


def save_layout(layout: Layout, directory: Path = LAYOUT_DIR) -> Path:
    from evpose.io.atomic import atomic_path

    path = layout_path(layout.name, directory)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(layout.to_dict(), indent=2) + "\n")
    return path
