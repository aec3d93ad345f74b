"""``evpose app``: the browser-based viewer (viser)."""

from __future__ import annotations

import time
from pathlib import Path


_DEFAULT_DATA = (Path("demo_data"), Path("maps"))


def default_data_folders(data: list[Path]) -> list[Path]:
    """The default ``--data`` resolved: ``demo_data`` and ``maps`` of the current folder when it has them, else the
    bundled ones of this checkout (so ``evpose app`` works from any folder); any other ``--data`` as given."""
    if tuple(data) != _DEFAULT_DATA or all(d.is_dir() for d in data):
        return list(data)
    bundled = [Path(__file__).resolve().parents[2] / d for d in _DEFAULT_DATA]
    return bundled if all(d.is_dir() for d in bundled) else list(data)


def check_arguments(data: list[Path], port: int, layout: str, export_dir: Path, cache_dir: Path | None) -> None:
    """Refuse what would otherwise start a server that cannot work as asked: a typo in ``--data`` served an empty
    browser, an unknown ``--layout`` a default one, and an out-of-range port ended in a bind() traceback."""
    from app.layouts import LAYOUT_DIR, layout_path

    from evpose.errors import InputError
    from evpose.io.atomic import check_outputs

    if not 0 <= port <= 65535:
        raise InputError(None, f"--port must be 0..65535, got {port}")
    for root in data:
        if not root.exists():
            raise InputError(root, "no such folder (--data takes folders of recordings and maps)")
        if not root.is_dir():
            raise InputError(root, "not a folder (--data takes folders of recordings and maps, not single files)")
    if not layout_path(layout).is_file():
        known = sorted(q.stem for q in LAYOUT_DIR.glob("*.json"))
        raise InputError(None, f"--layout {layout!r} is not in {LAYOUT_DIR} (known: {', '.join(known)})")
    check_outputs((), folders=(export_dir, cache_dir))


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
        data: Folders searched for recordings (*.h5, bags, ECD folders) and maps (*_map.ply, *_cloud.ply); nothing outside them is opened (default: demo_data and maps here, else the bundled ones).
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

    data = default_data_folders(list(data))
    check_arguments(data, port, layout, export_dir, cache_dir)
    cache = DiskCacheConfig(enabled=disk_cache, directory=cache_dir)
    viewer = ViewerApp(AppConfig(data=list(data), host=host, port=port, layout=layout, export_dir=export_dir,
                                 disk_cache=cache))
    print(f"evpose app: serving http://{host}:{port} (Ctrl+C to stop)", flush=True)
    try:
        while True:
            time.sleep(3600)
    finally:
        viewer.stop()
