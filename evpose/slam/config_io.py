"""Read and write :class:`SlamConfig` as YAML/JSON (the shared implementation in :mod:`evpose.io.config_file`)."""

from __future__ import annotations

from pathlib import Path

from evpose.io.config_file import config_from_dict, config_to_dict, read_config, write_config  # noqa: F401 - re-exported
from evpose.slam.config import SlamConfig


def load_slam_config(path: str | Path) -> SlamConfig:
    """Read a SlamConfig from ``.json`` or YAML; unknown keys and wrong types name their dotted path."""
    return read_config(SlamConfig, path)


def save_slam_config(cfg: SlamConfig, path: str | Path) -> None:
    """Write ``cfg`` atomically as JSON (``.json``) or YAML."""
    write_config(cfg, path)
