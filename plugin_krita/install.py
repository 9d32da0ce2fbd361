"""Install the Krita plug-in into a pykrita folder (``ssn-shadow install-plugin krita [--dest DIR] [--python PY]
[--link]``), or lay it out for its one-file package (:func:`stage`, ``ssn-shadow package krita``).
"""

from __future__ import annotations

import os
import shutil
import sys
from collections.abc import Mapping
from pathlib import Path

from ssn_engine.plugin_files import copy_host_kit, write_engine_config

PLUGIN_NAME = "ssn_shadow"
HERE = Path(__file__).resolve().parent
PACKAGE = HERE / PLUGIN_NAME
DESKTOP = HERE / f"{PLUGIN_NAME}.desktop"
_GENERATED = ("__pycache__", "*.pyc", "host_kit", "engine.json", ".gitignore")


def default_pykrita_dir(
    platform: str = sys.platform, env: Mapping[str, str] = os.environ, home: Path | None = None
) -> Path:
    """The user's pykrita folder: Krita's resource folder for this OS, plus ``pykrita``."""
    home = home or Path.home()
    if platform.startswith("win"):
        base = Path(env["APPDATA"]) if env.get("APPDATA") else home / "AppData" / "Roaming"
        return base / "krita" / "pykrita"
    if platform == "darwin":
        return home / "Library" / "Application Support" / "krita" / "pykrita"
    data = Path(env["XDG_DATA_HOME"]) if env.get("XDG_DATA_HOME") else home / ".local" / "share"
    return data / "krita" / "pykrita"


def _remove(path: Path) -> None:
    if path.is_symlink() or path.is_file():
        path.unlink()
    elif path.is_dir():
        shutil.rmtree(path)


def install(dest: Path | None = None, python: str | None = None, link: bool = False, configure: bool = True) -> Path:
    """Copy (or symlink, for development) the plug-in into ``dest`` (default: the user's pykrita
    folder), add the engine's shared modules and (``configure``) the ``engine.json`` naming ``python``; returns
    the plug-in package folder.

    Enable it afterwards in Krita: Settings > Configure Krita > Python Plugin Manager > Soft Shadow (SSN),
    then restart Krita; the docker is under Settings > Dockers > Soft Shadow.
    """
    dest = Path(dest) if dest is not None else default_pykrita_dir()
    dest.mkdir(parents=True, exist_ok=True)
    target, desktop = dest / PLUGIN_NAME, dest / DESKTOP.name
    for path in (target, desktop):
        _remove(path)
    if link:
        try:
            target.symlink_to(PACKAGE, target_is_directory=True)
            desktop.symlink_to(DESKTOP)
        except OSError as exc:
            raise OSError(f"cannot create symlinks in {dest} ({exc}); install without --link") from None
    else:
        shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns(*_GENERATED))
        shutil.copy2(DESKTOP, desktop)
    copy_host_kit(target, link)
    if configure:
        write_engine_config(target, _resolve_python(python))
    return target


def stage(root: Path) -> Path:
    """The plug-in as its package holds it (the importer's layout: the .desktop file beside the folder), with no
    engine.json (the package's Set up makes the engine); returns the plug-in folder."""
    return install(root, configure=False)


def _resolve_python(python: str | None) -> str | None:
    """An absolute path for a --python given as a path or as a command name on PATH."""
    if not python:
        return None
    if os.sep in python or (os.altsep and os.altsep in python):
        return str(Path(python).absolute())
    return shutil.which(python) or python
