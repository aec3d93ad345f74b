"""The viewer's own configuration (serving, data folders, caches) and the checks made before it starts."""

from __future__ import annotations

import socket
from dataclasses import dataclass, field
from pathlib import Path

from app.bookmarks import BOOKMARKS_NAME
from app.disk_cache import DiskCacheConfig
from app.frame_cache import FrameCacheConfig
from app.layouts import LAYOUT_DIR
from app.player import PlayerConfig
from evpose.errors import InputError


@dataclass
class AppConfig:
    """How the viewer is served and where it looks for data."""

    data: list[Path] = field(default_factory=lambda: [Path("demo_data"), Path("maps")])
    """Folders searched for recordings and maps; nothing outside them can be opened."""
    host: str = "127.0.0.1"
    """Interface to listen on (localhost by default)."""
    port: int = 8080
    """TCP port."""
    layout: str = "debug"
    """Layout from layouts/ applied at start."""
    export_dir: Path = Path("evpose_exports")
    """Where exports are written (also offered as browser downloads)."""
    layout_dir: Path = LAYOUT_DIR
    """Folder of layout files."""
    bookmarks_file: Path | None = None
    """The lesson bookmarks' file (app/bookmarks.py); None: ``bookmarks/bookmarks.json`` in :attr:`layout_dir`."""
    player: PlayerConfig = field(default_factory=PlayerConfig)
    """Pacing, coalescing and prefetch of the player."""
    frame_cache: FrameCacheConfig = field(default_factory=FrameCacheConfig)
    """Which steps the tracker's run-ahead keeps a display frame of, and the memory they may take."""
    disk_cache: DiskCacheConfig = field(default_factory=DiskCacheConfig)
    """Where the run-ahead's work is kept between openings of the same recording, map and configuration."""
    warm_up: bool = False
    """Prepare every recording's default pairing into the disk cache in a background process at the lowest CPU
    priority (``app/warm_up.py``), so the first far seek reads its pose from disk (9.5 s into the 10 s recording,
    player alone: drawn after 3-4 ms instead of 8.3-14 s, ``python -m app.bench --only far_seek``, load 2-7).
    ``evpose app`` turns it on (``--no-warm-up``: off); off here so viewers made in code (tests, benchmarks) start
    no process unless asked. Off whenever the disk cache is."""

    def bookmarks_path(self) -> Path:
        """Where the lesson bookmarks are kept."""
        return self.bookmarks_file if self.bookmarks_file is not None else self.layout_dir / BOOKMARKS_NAME


def check_port_free(host: str, port: int) -> None:
    """Raise a one-line error if the port is taken (viser would silently move to another port)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            raise InputError(None, f"cannot serve on {host}:{port}: {exc.strerror or exc}; is another viewer running? choose another --port") from None


def cache_inside_data(cfg: AppConfig) -> str:
    """Why the disk cache cannot be used where it is configured (it lies inside a data folder, where nothing is
    ever written), or "" when it can."""
    if not cfg.disk_cache.enabled:
        return ""
    cache = cfg.disk_cache.folder().resolve()
    for root in cfg.data:
        r = Path(root).expanduser().resolve()
        if cache == r or r in cache.parents:
            return (f"disk cache off: {cache} is inside the data folder {r}; "
                    "set disk_cache.directory (or XDG_CACHE_HOME) to a folder outside it")
    return ""
