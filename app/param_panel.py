"""The Parameters panel's behaviour: its controls follow the engine's configuration, a change re-runs the engine, and
reset / save / load act on configuration files (the controls themselves are built in app/viewer_controls.py).

Split out of app/server.py (session 29, which had grown past the project's 500-line limit). The note above the controls
is the engine's explanation; what the last button did stays above it until a control is moved (session 29: "load"
rebuilt the engine, whose note then replaced "loaded `my.yaml`" within a second, so a load seemed to do nothing; so did
"reset").
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import viser

from app.config_gui import ConfigGui, load_config_file
from app.engine import Engine
from app.export import write_config
from app.player import RerunFrom
from evpose.errors import EvposeError, InputError

if TYPE_CHECKING:
    from app.server import ViewerApp

CONFIG_SUFFIXES = (".yaml", ".yml", ".json")
"""File name endings "save" writes a configuration under (YAML, or JSON for ``.json``)."""


def rebuild_config_gui(app: ViewerApp, engine: Engine) -> None:
    """Controls for ``engine``'s configuration: new ones when its kind changed, else only the note above them."""
    rejected = getattr(engine, "rejected_config", None)
    if rejected is not None:
        # The tracker cannot start with these parameters (visible map min depth at its 10 m maximum: no map point
        # in view; mode "full" on a recording without IMU). Its controls stay, or come, so the value can be
        # changed; replaced by the events-only view's they could not, and tuned values were lost.
        shown, note = rejected, f"{engine.explanation} Change the parameters below to try again."
    else:
        # Not the class name ("TrackerConfig: changes re-run the tracker.", session 28): words a user reads.
        shown, note = engine.config, engine.explanation or "The tracker's parameters: a change re-runs it, from the point chosen above."
    if app.config_gui is not None and type(app.config_gui.config) is type(shown):
        # The controls are the source of the engine's config; pushing it back would fight a user still dragging.
        text = f"{app.param_said}\n\n{note}" if app.param_said else note
        if app.param_info.content != text:  # re-rendering the panel would steal a dragging user's focus
            app.param_info.content = text
        return
    if app.config_gui is not None:
        app.config_gui.remove()
    with app.params_tab:
        app.config_gui = ConfigGui(app.gui, shown, lambda config: edited(app, config))
    app.key_guard.watch(h for h in app.config_gui.handles.values() if isinstance(h, viser.GuiSliderHandle))
    app.param_said = ""  # other controls: what a button did to the earlier ones is past
    app.param_info.content = note


def edited(app: ViewerApp, config) -> None:
    """A control was moved (or reset): what the last button did is no longer the news."""
    app.param_said = ""
    config_changed(app, config)


def config_changed(app: ViewerApp, config) -> None:
    """A control changed: the engine is rebuilt with ``config`` from where the re-run dropdown says."""
    if app.player is not None:
        app.player.set_config(config, RerunFrom(app.rerun_dropdown.value))


def param_action(app: ViewerApp, action: str) -> None:
    """The configuration buttons: "reset", "save" or "load" (the file named in the "config file" box)."""
    if app.config_gui is None:
        return
    typed = app.config_path.value.strip()  # "   " was saved as a file named by three spaces
    try:
        if action in ("save", "load") and not typed:
            raise InputError(None, "type a file name in 'config file' first")
        if action == "reset":
            app.config_gui.reset()
            said = "configuration reset to defaults"
        elif action == "save":
            path = write_config(app.config_gui.config, config_save_path(app.cfg.export_dir, typed))
            said = f"saved `{path}`"
        elif action == "load":
            path = readable_config_path(app, typed)
            cfg = load_config_file(app.config_gui.cls, path)
            app.config_gui.set_config(cfg)
            config_changed(app, cfg)
            said = f"loaded `{path}`"
        else:
            return
    except (EvposeError, OSError) as exc:
        # OSError too (a 300-character name: "File name too long"): it ended in a traceback on the server's
        # console and the panel said nothing.
        said = f"**{action} failed:** {exc}"
    app.param_said = app.param_info.content = said


def export_path(export_dir: Path, path: str) -> Path:
    """Writes go to the export folder only, whatever path was typed (by file name)."""
    export_dir.mkdir(parents=True, exist_ok=True)
    return export_dir / Path(path).name


def config_save_path(export_dir: Path, typed: str) -> Path:
    """Where "save" writes a configuration: the export folder, a ``.yaml``/``.yml``/``.json`` name (``.yaml`` added
    to a name without a suffix). Any other suffix is refused: with ``--export-dir`` on a data folder, saving as
    ``landing.h5`` replaced the 2.5 MB recording by 4.8 kB of YAML."""
    path = export_path(export_dir, typed)
    if not path.suffix:
        return path.with_name(path.name + ".yaml")
    if path.suffix.lower() not in CONFIG_SUFFIXES:
        raise InputError(typed, f"a configuration is saved as {', '.join(CONFIG_SUFFIXES)}, not {path.suffix}")
    return path


def readable_config_path(app: ViewerApp, path: str) -> Path:
    """The file "load" reads: from the export folder first, else inside the data folders (nothing outside them)."""
    p = Path(path)
    export = (app.cfg.export_dir / p.name).resolve()
    if export.is_file() and (not p.is_absolute() or p.resolve() == export):
        return export
    if not p.is_absolute() and not p.exists() and not any((root / p).exists() for root in app.roots.roots):
        # A mistyped name of a saved file was "refused: outside the data directories", as if it were forbidden.
        raise InputError(path, f"no such file in the export folder {app.cfg.export_dir} or the data folders")
    return app.roots.check(p)
