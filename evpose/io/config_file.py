"""Configuration dataclasses as YAML/JSON files: one implementation for the tracker, SLAM and the viewer.

Files hold a nested mapping mirroring the dataclasses; missing keys keep their
defaults, unknown keys and wrong types are an :class:`InputError` naming the
dotted field (a typo must not silently do nothing).
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
import types
import typing
from pathlib import Path

from evpose.errors import InputError
from evpose.io.atomic import atomic_path


def config_to_dict(cfg) -> dict:
    """Nested plain dict (enums as their values) of a config dataclass."""
    out = {}
    for f in dataclasses.fields(cfg):
        v = getattr(cfg, f.name)
        if dataclasses.is_dataclass(v):
            v = config_to_dict(v)
        elif isinstance(v, enum.Enum):
            v = v.value
        out[f.name] = v
    return out


def shown(value, limit: int = 80) -> str:
    """``repr(value)`` for a message, cut to about ``limit`` characters. A plain repr of what a file holds can be
    endless: a YAML alias chain ("billion laughs", 9 levels of 9 references: 40 bytes a level) hung the command."""
    import reprlib

    r = reprlib.Repr()
    r.maxlevel, r.maxlist, r.maxtuple, r.maxdict, r.maxstring, r.maxother = 2, 4, 4, 4, limit, limit
    text = r.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _convert(typ, raw, meta):
    """``raw`` as a value of the field type ``typ`` (ValueError naming what was expected). Numbers must be finite and
    inside ``meta``'s min..max; optional fields take null, tuples their number of values."""
    origin = typing.get_origin(typ)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(typ)
        if raw is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return _convert(inner[0], raw, meta) if len(inner) == 1 else raw
    if origin is tuple:
        # e.g. MapBuildConfig.viewpoint (x, y, z): "abc" or [1, 2] ended in tracebacks deep in the builder.
        args = typing.get_args(typ)
        if not isinstance(raw, (list, tuple)):
            raise ValueError(f"expected a list of {len(args)} values, got {shown(raw)}")
        if len(raw) != len(args):
            raise ValueError(f"expected {len(args)} values, got {len(raw)}")
        return tuple(_convert(a, v, {}) for a, v in zip(args, raw))
    if isinstance(typ, type) and issubclass(typ, enum.Enum):
        choices = ", ".join(str(m.value) for m in typ)
        if isinstance(raw, bool) or not isinstance(raw, (str, int, float)):
            raise ValueError(f"expected one of {choices}, got {shown(raw)}")
        try:
            return typ(raw)
        except ValueError:
            raise ValueError(f"expected one of {choices}, got {shown(raw)}") from None
    if typ is bool:
        if not isinstance(raw, bool):
            raise ValueError(f"expected true/false, got {shown(raw)}")
        return raw
    if typ is int:
        try:
            whole = not isinstance(raw, bool) and isinstance(raw, (int, float, str)) and float(raw) == int(float(raw))
        except (ValueError, OverflowError):  # OverflowError: int(inf)
            whole = False
        if not whole:
            raise ValueError(f"expected an integer, got {shown(raw)}")
        value = int(raw) if isinstance(raw, int) else int(float(raw))
        if not -(2**63) <= value < 2**63:
            # A field without a declared range (SlamConfig.seed) took 1e300 and numpy's seeding ended in
            # "OverflowError: Python int too large to convert to C long" (session 30's fuzzing).
            raise ValueError(f"expected an integer that fits in 64 bits, got {shown(raw)}")
        _check_range(value, meta)
        return value
    if typ is float:
        if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
            raise ValueError(f"expected a number, got {shown(raw)}")
        try:
            value = float(raw)
        except ValueError:
            raise ValueError(f"expected a number, got {shown(raw)}") from None
        except OverflowError:
            # An integer of 309 digits or more (YAML and JSON read it exactly) does not fit a float: "OverflowError: int
            # too large to convert to float", a traceback out of every --config (session 32's fuzzing, /tmp/s32/sig32/).
            raise ValueError(f"expected a finite number, got {shown(raw)}") from None
        _check_range(value, meta)
        return value
    return raw


def config_from_dict(cls, data: dict, source: str | None = None, prefix: str = ""):
    """Build dataclass ``cls`` from a nested dict; unknown keys and wrong types raise :class:`InputError`."""
    if not isinstance(data, dict):
        raise InputError(source, f"expected a mapping, got {type(data).__name__}", prefix.rstrip(".") or None)
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    # Sorted as text: YAML keys may be numbers too, and sorting 1 with "foo" was a TypeError traceback.
    unknown = sorted(set(data) - names, key=str)
    if unknown:
        raise InputError(source, f"unknown setting (known: {', '.join(sorted(names))})", prefix + shown(unknown[0]).strip("'"))
    kwargs = {}
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for name, raw in data.items():
        typ = hints[name]
        key = prefix + name
        if dataclasses.is_dataclass(typ):
            kwargs[name] = config_from_dict(typ, raw, source, key + ".")
            continue
        try:
            kwargs[name] = _convert(typ, raw, fields[name].metadata)
        except (TypeError, ValueError) as exc:
            raise InputError(source, str(exc), key) from None
    return cls(**kwargs)


def check_config(cfg, prefix: str = "") -> None:
    """Every number of a config dataclass (nested ones too) finite and inside its field's ``min``..``max``.

    :func:`config_from_dict` checks what a file sets; commands call this after applying their flags, so
    ``--spacing nan`` or ``--k 0`` is the same one-line error as in a file, not a traceback or a silent run.
    """
    for f in dataclasses.fields(cfg):
        value, key = getattr(cfg, f.name), prefix + f.name
        if dataclasses.is_dataclass(value):
            check_config(value, key + ".")
            continue
        numbers = value if isinstance(value, (tuple, list)) else (value,)
        for v in numbers:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                continue
            try:
                _check_range(v, f.metadata if v is value else {})
            except ValueError as exc:
                raise InputError(None, str(exc), key) from None


def _check_range(value, meta) -> None:
    """A number must be finite and inside the field's declared ``min``..``max`` (the range the viewer's slider
    offers): a negative window or a NaN decay would otherwise run and quietly produce nonsense."""
    # An integer is finite however large (math.isfinite(10**400) is an OverflowError: a traceback out of `build-map
    # --k 999...9`, session 32); Python compares it with a float bound exactly.
    if not isinstance(value, int) and not math.isfinite(value):
        raise ValueError(f"expected a finite number, got {value!r}")
    lo, hi = meta.get("min"), meta.get("max")
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ValueError(f"{shown(value)} is outside the allowed range {lo}..{hi}{unit}")


def _unique_keys(pairs: list) -> dict:
    """JSON object hook: a key given twice is an error (both parsers kept the last value silently)."""
    keys = [k for k, _ in pairs]
    dup = next((k for i, k in enumerate(keys) if k in keys[:i]), None)
    if dup is not None:
        raise ValueError(f"duplicate key {dup!r}")
    return dict(pairs)


def _load_yaml(text: str):
    """``yaml.safe_load`` refusing a key given twice in one mapping, with the line of the second."""
    import yaml

    class UniqueKeyLoader(yaml.SafeLoader):
        def construct_mapping(self, node, deep=False):
            seen = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"duplicate key {key!r}", key_node.start_mark)
                seen.add(key)
            return super().construct_mapping(node, deep)

    return yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass


def read_config(cls, path: str | Path):
    """Read dataclass ``cls`` from ``.yaml``/``.yml``/``.json``; missing keys keep their defaults."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(path, f"cannot read the config file ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(path, "not a text file (a config file is UTF-8 YAML or JSON)") from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text, object_pairs_hook=_unique_keys)
        else:
            data = _load_yaml(text)
    except Exception as exc:  # noqa: BLE001 - any parser error is bad input
        # Both parsers know where they stopped (JSONDecodeError.lineno, YAML's problem_mark): name that line.
        mark = getattr(exc, "problem_mark", None)
        line = getattr(exc, "lineno", None) or (mark.line + 1 if mark is not None else None)
        what = "JSON" if path.suffix.lower() == ".json" else "YAML"
        detail = getattr(exc, "problem", None) or getattr(exc, "msg", None) or str(exc).splitlines()[0]
        raise InputError(path, f"not valid {what} ({detail})", f"line {line}" if line else None) from None
    # `data or {}` read a file holding `false` or `0` as the defaults.
    return config_from_dict(cls, {} if data is None else data, str(path))


def write_config(cfg, path: str | Path) -> None:
    """Write a config dataclass atomically as JSON (``.json``) or YAML (anything else)."""
    path = Path(path)
    data = config_to_dict(cfg)
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".json":
            tmp.write_text(json.dumps(data, indent=2) + "\n")
        else:
            import yaml

            tmp.write_text(yaml.safe_dump(data, sort_keys=False))
