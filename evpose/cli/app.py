"""``evpose app``: the browser-based viewer (viser)."""

from __future__ import annotations

import time
from pathlib import Path


def main(
    data: list[Path] = [Path("demo_data"), Path("maps")],  # noqa: B006 - tyro reads the default
    host: str = "127.0.0.1",
    port: int = 8080,
    layout: str = "debug",
    export_dir: Path = Path("evpose_exports"),
    cache_dir: Path | None = None,
    disk_cache: bool = True,
) -> int:
    """Start the browser-based viewer: browse, play, step and tune the tracker on recordings and maps.

    Args:
        data: Folders searched for recordings (*.h5, bags, ECD folders) and maps (*_map.ply, *_cloud.ply); nothing outside them is opened.
        host: Interface to listen on; localhost by default.
        port: TCP port; the command fails with a clear message if it is taken.
        layout: Layout name from layouts/ (debug, teaching, compare, or one you saved).
        export_dir: Folder for exported trajectories, configurations, screenshots and GIFs.
        cache_dir: Where computed steps are kept between openings of the same recording, map, configuration and
            code (default ``$XDG_CACHE_HOME/evpose/viewer``, i.e. ``~/.cache/evpose/viewer``; never inside a data folder).
        disk_cache: Keep and reuse computed steps in the cache folder (``--no-disk-cache``: compute afresh, write nothing).
    """
    from app.disk_cache import DiskCacheConfig
    from app.server import AppConfig, ViewerApp

    cache = DiskCacheConfig(enabled=disk_cache, directory=cache_dir)
    viewer = ViewerApp(AppConfig(data=list(data), host=host, port=port, layout=layout, export_dir=export_dir,
                                 disk_cache=cache))
    print(f"evpose app: serving http://{host}:{port} (Ctrl+C to stop)", flush=True)
    try:
        while True:
            time.sleep(3600)
    finally:
        viewer.stop()
