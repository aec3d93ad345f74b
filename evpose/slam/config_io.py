"""Read and write :class:`SlamConfig` as YAML/JSON; unknown keys and wrong types are reported with their dotted path."""

from __future__ import annotations

import dataclasses
import enum
import json
import typing
from pathlib import Path

from evpose.errors import InputError
from evpose.io.atomic import atomic_path
from evpose.slam.config import SlamConfig


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


def config_from_dict(cls, data: dict, source: str | None = None, prefix: str = ""):
    """Build ``cls`` from ``data``; missing keys keep defaults."""
    if not isinstance(data, dict):
        raise InputError(source, f"{prefix or 'config'} must be a mapping, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    for key in data:
        if key not in names:
            raise InputError(source, f"unknown key {prefix + str(key)!r} (known: {', '.join(sorted(names))})")
    kwargs = {}
    for name, value in data.items():
        tp = hints[name]
        where = prefix + name
        if dataclasses.is_dataclass(tp):
            kwargs[name] = config_from_dict(tp, value, source, where + ".")
        elif isinstance(tp, type) and issubclass(tp, enum.Enum):
            try:
                kwargs[name] = tp(value)
            except ValueError:
                raise InputError(source, f"{where} must be one of {[m.value for m in tp]}, got {value!r}") from None
        elif tp is bool:
            if not isinstance(value, bool):
                raise InputError(source, f"{where} must be true or false, got {value!r}")
            kwargs[name] = value
        elif tp in (int, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or (tp is int and not float(value).is_integer()):
                raise InputError(source, f"{where} must be a number ({tp.__name__}), got {value!r}")
            kwargs[name] = tp(value)
        else:
            kwargs[name] = value
    return cls(**kwargs)


def load_slam_config(path: str | Path) -> SlamConfig:
    """Read a SlamConfig from ``.json`` or YAML."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(path, f"cannot read the config file ({exc.strerror})") from None
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            import yaml

            data = yaml.safe_load(text)
    except Exception as exc:  # noqa: BLE001 - any parser error is bad input
        raise InputError(path, f"not valid {'JSON' if path.suffix.lower() == '.json' else 'YAML'} ({str(exc).splitlines()[0]})") from None
    return config_from_dict(SlamConfig, data or {}, str(path))


def save_slam_config(cfg: SlamConfig, path: str | Path) -> None:
    """Write ``cfg`` atomically as JSON (``.json``) or YAML."""
    path = Path(path)
    data = config_to_dict(cfg)
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".json":
            tmp.write_text(json.dumps(data, indent=2) + "\n")
        else:
            import yaml

            tmp.write_text(yaml.safe_dump(data, sort_keys=False))
