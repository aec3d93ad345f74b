"""GUI controls generated from configuration dataclasses (the same ones tyro turns into the CLI).

Walks a dataclass recursively: nested dataclasses become folders, enums
dropdowns, bools checkboxes, numbers sliders when ``metadata`` gives min/max
(else number inputs), everything else a text input holding JSON. Each control's
hint is the field's attribute docstring plus its unit. An integer field whose 0
means something else (``metadata["zero"]``: "off", "automatic") gets a checkbox
for that 0 under its slider, which then offers the other values only.
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import functools
import inspect
import json
import textwrap
import threading
import types
import typing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable


from evpose.errors import ConfigError, InputError


@dataclass(frozen=True)
class FieldSpec:
    """One leaf field of a (nested) configuration dataclass."""

    path: tuple[str, ...]
    """Attribute names from the root config down to this field."""
    type: Any
    """Resolved annotation."""
    default: Any
    metadata: dict
    doc: str
    """Attribute docstring (may be empty)."""

    @property
    def name(self) -> str:
        return ".".join(self.path)

    @property
    def label(self) -> str:
        """The control's label: the field name in words, its unit in brackets. A name ending in its unit says it once:
        "rate hz [Hz]", "velocity window ms [ms]", "field margin px [px]" (60 of the tracker's and SLAM's controls) read
        "rate [Hz]", "velocity window [ms]", "field margin [px]"."""
        unit = self.metadata.get("unit")
        words = self.path[-1].split("_")
        if unit and words[-1].lower() == str(unit).lower():
            if len(words) == 1:
                return words[0]  # "iterations [iterations]"
            words = words[:-1]
        base = " ".join(words)
        return f"{base} [{unit}]" if unit else base


@functools.lru_cache(maxsize=None)
def attribute_docs(cls: type) -> dict[str, str]:
    """Attribute docstrings (a string literal right under a field) of a class and the classes it derives from (a
    config split into groups of fields, such as the SLAM's ``TrackingConfig``), by field name."""
    out: dict[str, str] = {}
    for base in reversed(cls.__mro__[1:]):
        if base is not object:
            out.update(attribute_docs(base))
    out.update(_own_attribute_docs(cls))
    return out


def _own_attribute_docs(cls: type) -> dict[str, str]:
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return {}
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    out: dict[str, str] = {}
    for prev, node in zip(body, body[1:]):
        if isinstance(prev, ast.AnnAssign) and isinstance(prev.target, ast.Name):
            if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
                out[prev.target.id] = " ".join(node.value.value.split())
    return out


def _unwrap_optional(tp):
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0], True
    return tp, False


def field_specs(config) -> list[FieldSpec]:
    """Leaf fields of a config instance (or class), depth first in declaration order."""
    cls = config if isinstance(config, type) else type(config)
    inst = config if not isinstance(config, type) else cls()
    return list(_walk(cls, inst, ()))


def _walk(cls, inst, prefix):
    hints = typing.get_type_hints(cls)
    docs = attribute_docs(cls)
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        tp = hints.get(f.name, f.type)
        value = getattr(inst, f.name)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            yield from _walk(type(value), value, prefix + (f.name,))
            continue
        yield FieldSpec(prefix + (f.name,), tp, value, dict(f.metadata), docs.get(f.name, ""))


def get_path(config, path: tuple[str, ...]):
    for name in path:
        config = getattr(config, name)
    return config


def replace_path(config, path: tuple[str, ...], value):
    """A copy of ``config`` with the field at ``path`` set to ``value`` (nested dataclasses copied, not mutated)."""
    if len(path) == 1:
        return dataclasses.replace(config, **{path[0]: value})
    child = getattr(config, path[0])
    return dataclasses.replace(config, **{path[0]: replace_path(child, path[1:], value)})


def to_plain(config) -> dict:
    """A JSON/YAML-safe nested dict of a config (enums by value, tuples as lists, paths as strings)."""

    def conv(v):
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            return {f.name: conv(getattr(v, f.name)) for f in dataclasses.fields(v) if f.init}
        if isinstance(v, enum.Enum):
            return v.value
        if isinstance(v, (tuple, list)):
            return [conv(x) for x in v]
        if isinstance(v, Path):
            return str(v)
        if hasattr(v, "tolist"):
            return v.tolist()
        return v

    return conv(config)


def coerce(spec: FieldSpec, value):
    """Convert a value from a widget or a file to the field's type; ConfigError if impossible."""
    tp, optional = _unwrap_optional(spec.type)
    if value is None or (optional and value == ""):
        if optional:
            return None
        raise ConfigError(f"{spec.name}: a value is required")
    try:
        if isinstance(tp, type) and issubclass(tp, enum.Enum):
            return tp(value)
        if tp is bool:
            if isinstance(value, str):
                return value.strip().lower() in ("1", "true", "yes", "on")
            return bool(value)
        if tp is int:
            return int(round(float(value)))
        if tp is float:
            return float(value)
        if tp is str:
            return str(value)
        if tp is Path:
            return Path(value)
        if isinstance(value, str):
            value = json.loads(value)
        origin = typing.get_origin(tp)
        if origin in (tuple, list):
            return origin(value)
        return value
    except (ValueError, TypeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"{spec.name}: cannot use {value!r} ({exc})") from None


def from_plain(cls: type, data: dict, source: str | None = None):
    """Build a config of class ``cls`` from a nested dict; unknown keys are refused with their path."""
    if not isinstance(data, dict):
        raise InputError(source, "configuration must be a mapping")
    cfg = cls()
    specs = {s.path: s for s in field_specs(cfg)}
    nested = {s.path[: i + 1] for s in specs.values() for i in range(len(s.path) - 1)}

    def walk(d: dict, prefix: tuple[str, ...]):
        nonlocal cfg
        for key, value in d.items():
            path = prefix + (str(key),)
            if path in specs:
                try:
                    cfg = replace_path(cfg, path, coerce(specs[path], value))
                except ConfigError as exc:
                    raise InputError(source, str(exc), ".".join(path)) from None
            elif path in nested and isinstance(value, dict):
                walk(value, path)
            else:
                raise InputError(source, "unknown configuration field", ".".join(path))

    walk(data, ())
    return cfg


def load_config_file(cls: type, path: str | Path):
    """Read a YAML/JSON configuration file (the engine's own reader, so files are interchangeable with the CLI's)."""
    from evpose.io.config_file import read_config

    return read_config(cls, path)


def save_config_file(config, path: str | Path) -> None:
    from evpose.io.config_file import write_config

    write_config(config, path)


def on_default_grid(lo: int, step: int, default: int) -> int:
    """The slider minimum for an integer field: the lowest value >= ``lo`` on the default's grid of ``step``.

    A browser slider offers only ``min + k * step``. The TDF blur (default 3, min 0, step 2, odd kernels) offered
    0, 2, 4..., none of them odd: the slider read 4 while the field blurred with 5 (even sizes are rounded up), and
    the default could not be dragged back to. SLAM's ``klt_upsample_window_px`` (default 35, odd, 0: automatic) offers
    1, 3, ... 101 (its 0 is a checkbox, see ``ConfigGui._zero_box``); ``event_registration.min_events`` starts at 10."""
    return lo + (default - lo) % step if step > 0 and lo <= default else lo


class ConfigGui:
    """Controls for every leaf field of a config; ``on_change(new_config)`` fires on each edit."""

    def __init__(self, gui, config, on_change: Callable[[object], None]):
        self.gui = gui
        self.cls = type(config)
        self.config = config
        self.on_change = on_change
        self.handles: dict[tuple[str, ...], Any] = {}
        self._muted = False
        self._lock = threading.Lock()
        self._folders: dict[tuple[str, ...], Any] = {}
        self.zero_boxes: dict[tuple[str, ...], Any] = {}
        """Field path -> the checkbox that sets it to its special 0 (metadata ``"zero"``: "off", "automatic")."""
        for spec in field_specs(config):
            self._add(spec)

    def _container(self, path: tuple[str, ...]):
        # Nested dataclasses become (collapsed) folders, created in declaration order.
        if not path:
            return None
        if path not in self._folders:
            parent = self._container(path[:-1])
            if parent is not None:
                with parent:
                    self._folders[path] = self.gui.add_folder(path[-1].replace("_", " "), expand_by_default=False)
            else:
                self._folders[path] = self.gui.add_folder(path[-1].replace("_", " "), expand_by_default=False)
        return self._folders[path]

    def _add(self, spec: FieldSpec) -> None:
        folder = self._container(spec.path[:-1])
        if folder is not None:
            with folder:
                handle = self._widget(spec)
                box = self._zero_box(spec, handle)
        else:
            handle = self._widget(spec)
            box = self._zero_box(spec, handle)
        self.handles[spec.path] = handle
        for h in (handle, box) if box is not None else (handle,):
            h.on_update(lambda _event, spec=spec, handle=handle: self._edited(spec, handle))

    def _zero_box(self, spec: FieldSpec, slider):
        """For an integer slider whose 0 means something else (metadata ``"zero"``: "off", "automatic"), a checkbox
        under it that sets that 0; the slider then offers the other values only (odd kernel sizes from 1).

        A slider offers ``min + k * step``: with 0 on its grid a kernel-size slider offered even sizes (the coarse
        TDF blur: 2 shown, 3 used), and with 1 as its minimum the 0 could be set in a configuration file only
        (``klt_upsample_window_px`` 0: "automatic")."""
        zero = spec.metadata.get("zero")
        if zero is None or not hasattr(slider, "step"):
            return None
        box = self.gui.add_checkbox(f"{spec.path[-1].replace('_', ' ')}: {zero}", spec.default == 0,
                                    hint=f"Checked: {spec.path[-1]} is 0 ({zero}); the slider above is not used. "
                                         + (spec.doc or ""))
        slider.disabled = box.value
        self.zero_boxes[spec.path] = box
        return box

    def _edited(self, spec: FieldSpec, handle) -> None:
        if self._muted:
            return
        box = self.zero_boxes.get(spec.path)
        if box is not None:
            if handle.disabled != box.value:
                handle.disabled = box.value
            if box.value:
                self._hand_over(spec, 0)
                return
        try:
            value = coerce(spec, handle.value)
        except ConfigError:
            return  # half-typed text: wait for a valid value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            lo, hi = getattr(handle, "min", None), getattr(handle, "max", None)  # number boxes may have one or none
            clamped = type(value)(min(max(value, lo if lo is not None else value), hi if hi is not None else value))
            if clamped != value:
                # Typed into the slider's box past an end (rate 5000 Hz of 10-1000): the box showed it and the
                # tracker ran with it, a value a configuration file is refused for. Shown and used at the end;
                # the write calls back here at once with it.
                handle.value = clamped
                return
        self._hand_over(spec, value)

    def _hand_over(self, spec: FieldSpec, value) -> None:
        # viser runs update callbacks on a thread pool: two controls moved at once (two tabs) each copied the
        # config without the other's change, and the later write dropped the earlier control's value while its
        # slider still showed it. Read, write and hand over in one piece, so the last config handed over has both.
        with self._lock:
            if value == get_path(self.config, spec.path):
                return
            self.config = replace_path(self.config, spec.path, value)
            self.on_change(self.config)

    def _widget(self, spec: FieldSpec):
        tp, optional = _unwrap_optional(spec.type)
        hint = spec.doc or None
        md = spec.metadata
        value = spec.default
        if isinstance(tp, type) and issubclass(tp, enum.Enum):
            return self.gui.add_dropdown(spec.label, [m.value for m in tp], initial_value=tp(value).value, hint=hint)
        if tp is bool:
            return self.gui.add_checkbox(spec.label, bool(value), hint=hint)
        if tp in (int, float) and value is not None:
            lo, hi = md.get("min"), md.get("max")
            step = md.get("step", 1 if tp is int else None)
            if lo is not None and hi is not None:
                if step is None:
                    step = (hi - lo) / 100.0
                if tp is int and md.get("zero") is not None and lo <= 0:
                    lo = 1  # 0 is the checkbox's (_zero_box); the slider's grid starts at 1 (odd kernel sizes)
                lo = on_default_grid(lo, step, value) if tp is int else lo
                return self.gui.add_slider(spec.label, min=lo, max=hi, step=step, initial_value=min(max(value, lo), hi), hint=hint)
            return self.gui.add_number(spec.label, value, min=lo, max=hi, step=step, hint=hint)
        text = "" if value is None else (value if isinstance(value, str) else json.dumps(to_plain(value)))
        return self.gui.add_text(spec.label, str(text), hint=hint)

    def set_config(self, config) -> None:
        """Show ``config`` in the controls without firing ``on_change``."""
        self.config = config
        self._muted = True
        try:
            for spec in field_specs(config):
                handle = self.handles.get(spec.path)
                if handle is None:
                    continue
                v = spec.default
                if isinstance(v, enum.Enum):
                    v = v.value
                elif not isinstance(v, (bool, int, float, str)) and v is not None:
                    v = json.dumps(to_plain(v))
                elif v is None:
                    v = ""
                box = self.zero_boxes.get(spec.path)
                if box is not None:
                    box.value = handle.disabled = v == 0
                    if v == 0:
                        continue  # the slider keeps its last value, for when the box is unchecked
                handle.value = v
        finally:
            self._muted = False

    def reset(self) -> None:
        self.set_config(self.cls())
        self.on_change(self.config)

    def remove(self) -> None:
        for h in (*self.handles.values(), *self.zero_boxes.values()):
            h.remove()
        self.zero_boxes.clear()
        # Innermost first: removing a folder also removes the folders inside it (a second remove warns).
        for _, f in sorted(self._folders.items(), key=lambda kv: -len(kv[0])):
            f.remove()
        self.handles.clear()
        self._folders.clear()
