"""Layouts: which panels are shown, where they dock, and what the 3D view shows; JSON files in ``layouts/``."""

from __future__ import annotations

import dataclasses
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from app.scene import SceneToggles
from app.teaching import Stage
from evpose.errors import InputError
from evpose.io.json_file import read_json

LAYOUT_DIR = Path(__file__).resolve().parent.parent / "layouts"
"""The repository's ``layouts/`` folder."""

SHIPPED = ("compare", "debug", "teaching")
"""The layouts that come with evpose, in :data:`LAYOUT_DIR`. Saving under one of their names there is refused (session
29: "save as debug" replaced the checkout's ``layouts/debug.json``, the default ``--layout``, without a word, and only
git brought it back); in another layout folder any name may be saved over."""

PANELS = ("images", "plots", "teaching", "parameters")
"""The movable panels a layout places (the main control panel always stays docked left)."""

_DOCK = re.compile(r"^(left|right|float|(above|below):(images|plots|teaching|parameters))$")
EDGES = ("left", "right", "float")
"""Docks that need no other panel."""
MIN_WIDTH = 160
"""Narrowest panel width a layout sets, CSS pixels (a narrower column leaves its controls unreadable)."""
MAX_WIDTH = 1600
"""Widest panel width a layout sets, CSS pixels."""
CONTROL_PANEL_PX = 320
"""Width of viser's main control panel at control_width='medium' (20 em x 16 px); it is always docked left."""
DEFAULT_COLUMN_PX = 300
"""Width viser gives a newly docked column (its DEFAULT_REGION_PX)."""
NARROW_WINDOW_PX = 1280
"""Narrowest browser window the shipped layouts are made for, CSS pixels (a common laptop width); in narrower ones
their panels are placed in one right column (app/window_fit.py)."""
MIN_VIEW_PX = 360
"""Width of 3D view every shipped layout leaves in a NARROW_WINDOW_PX window, CSS pixels. Session 12's debug layout
left 220 px (a sliver), and compare's floating images (360 px) covered its 260 px view and overlapped the plots."""


def dock_choices(name: str) -> list[str]:
    """The docks a panel can be given: the edges, float, and above/below every other panel (never itself)."""
    return [*EDGES] + [f"{side}:{p}" for p in PANELS if p != name for side in ("above", "below")]


def dock_anchor(dock: str) -> str | None:
    """The panel a dock stacks on ('below:images' -> 'images'), None for left/right/float."""
    return dock.split(":", 1)[1] if ":" in dock else None


def _check_docks(panels: dict[str, "PanelPlacement"], source: str | None) -> None:
    """Refuse a panel stacked on itself and stacks that go round in a circle (neither could be placed first)."""
    for name in panels:
        seen = [name]
        anchor = dock_anchor(panels[name].dock)
        while anchor is not None:
            if anchor in seen:
                what = "on itself" if seen == [name] else "in a circle: " + " -> ".join(seen + [anchor])
                raise InputError(source, f"dock {panels[name].dock!r} stacks the panel {what}", f"panels.{name}")
            seen.append(anchor)
            anchor = dock_anchor(panels[anchor].dock)


def check_width(width, source: str | None = None, key: str = "width") -> int | None:
    """A layout width: None (viewer default) or whole CSS pixels in [MIN_WIDTH, MAX_WIDTH]."""
    if width is None:
        return None
    if isinstance(width, bool) or not isinstance(width, (int, float)) or width != int(width):
        raise InputError(source, f"width {width!r} must be whole pixels or null", key)
    if not MIN_WIDTH <= width <= MAX_WIDTH:
        raise InputError(source, f"width {int(width)} is outside {MIN_WIDTH}-{MAX_WIDTH} px", key)
    return int(width)


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
    stage: str | None = None
    """The teaching panel's stage when the layout is applied (None: left as it is). A lesson starts at its first
    stage: the teaching layout opened on the TDF, the third of six, before "< previous" / "next >" walked them
    (session 28); a teacher's saved layout keeps the stage it was saved at."""

    def to_dict(self) -> dict:
        return {
            "name": self.name, "description": self.description, "dark_mode": self.dark_mode,
            "panels": {k: dataclasses.asdict(v) for k, v in self.panels.items()},
            "scene": dataclasses.asdict(self.scene),
            "stage": self.stage,
        }

    @classmethod
    def from_dict(cls, data, source: str | None = None) -> "Layout":
        """Validate a parsed layout file; every problem names the offending key."""
        if not isinstance(data, dict):
            raise InputError(source, "a layout must be a JSON object")
        unknown = set(data) - {"name", "description", "dark_mode", "panels", "scene", "stage"}
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
            placement.width = check_width(placement.width, source, f"panels.{key}.width")
            placement.visible = bool(placement.visible)
            panels[key] = placement
        _check_docks(panels, source)
        try:
            scene = SceneToggles(**(data.get("scene") or {}))
        except TypeError as exc:
            raise InputError(source, str(exc), "scene") from None
        stage = data.get("stage")
        if stage is not None and stage not in {s.value for s in Stage}:
            raise InputError(source, f"stage {stage!r} is none of {', '.join(s.value for s in Stage)}", "stage")
        return cls(name, str(data.get("description", "")), bool(data.get("dark_mode", False)), panels, scene, stage)


    def with_dock(self, name: str, dock: str) -> "Layout":
        """A copy with one panel's dock changed; an unknown dock, or one stacking panels in a circle, raises InputError."""
        data = self.to_dict()
        data["panels"][name]["dock"] = dock
        return Layout.from_dict(data, f"{name} dock")

    def placements(self) -> list[tuple[str, str]]:
        """(panel, dock as shown) for the visible panels, in an order where every anchor is placed before the panels on it.

        A panel stacked on a hidden panel takes that panel's place (its dock as shown), so
        'below:images' with images hidden docks where images would be. A panel stacked on a
        floating one docks on the right edge (a stack needs a docked neighbour; viser does the same).
        """
        shown: dict[str, str] = {}

        def resolve(name: str) -> str:
            # Hidden panels resolve too, as the place their dependants take; no cycles (from_dict refuses them).
            dock = self.panels[name].dock
            anchor = dock_anchor(dock)
            if anchor is None:
                return dock
            if not self.panels[anchor].visible:
                return resolve(anchor)
            return "right" if resolve(anchor) == "float" else dock

        for name in PANELS:
            shown[name] = resolve(name)
        order: list[str] = []
        pending = [p for p in PANELS if self.panels[p].visible]
        while pending:  # anchors first; terminates because shown docks only name visible, acyclic anchors
            ready = [p for p in pending if dock_anchor(shown[p]) in (None, *order)]
            order += ready
            pending = [p for p in pending if p not in ready]
        return [(p, shown[p]) for p in order]


    def region_widths(self) -> dict[str, int]:
        """Width to command for each docked edge, CSS pixels: the sum of the columns docked there.

        viser's ``set_width`` on a docked panel sets the width of its whole edge and shares it
        among the columns there in proportion to their current widths. So a panel's width is
        reached by asking for the edge's total: each column at its panel's width (the first
        width set among the panels stacked in it, else viser's default), plus the main panel on the left.
        """
        shown = dict(self.placements())
        columns: dict[str, list[str]] = {}
        for name, dock in shown.items():
            root = name
            while dock_anchor(shown[root]) is not None:
                root = dock_anchor(shown[root])
            columns.setdefault(root, []).append(name)
        totals = {"left": CONTROL_PANEL_PX, "right": 0}
        for root, members in columns.items():
            if shown[root] in totals:
                widths = [self.panels[p].width for p in members if self.panels[p].width]
                totals[shown[root]] += widths[0] if widths else DEFAULT_COLUMN_PX
        return totals

    def view_width(self, window_px: int) -> int:
        """Width the 3D view keeps in a browser window this wide, CSS pixels: the window less both docked edges."""
        widths = self.region_widths()
        return window_px - widths["left"] - widths["right"]


def layout_path(name: str, directory: Path = LAYOUT_DIR) -> Path:
    """File of a layout name; names are plain words so a name can never point outside the folder."""
    if not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", name or ""):
        raise InputError(None, f"layout name {name!r} must be 1-64 letters, digits, '_' or '-'")
    return directory / f"{name}.json"


def load_layout(path: str | Path) -> Layout:
    path = Path(path)
    return Layout.from_dict(read_json(path), str(path))


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
    if layout.name in SHIPPED and Path(directory).resolve() == LAYOUT_DIR.resolve():
        raise InputError(path, f"{layout.name!r} is a layout shipped with evpose: save under another name")
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(layout.to_dict(), indent=2) + "\n")
    return path
