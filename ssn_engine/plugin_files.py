"""Files every host plug-in gets at install time (stdlib only).

The plug-ins run inside the host's own Python, which has no numpy, so they
carry copies of the engine's stdlib-only modules, the host kit: the worker
client and its protocol framing, the engine.json reader, the light map, its
editor and its picture, and the shared defaults. ``engine.json`` names the
Python that runs ``ssn-shadow serve``.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

SHARED_MODULES = (  # the host kit
    "client.py",
    "defaults.py",
    "engine_config.py",
    "light_editor.py",
    "light_map.py",
    "light_map_picture.py",
    "protocol.py",
)
SHARED_PACKAGE = "engine_shared"
CONFIG_NAME = "engine.json"


def copy_shared_modules(plugin_dir: Path) -> Path:
    """Copy the toolkit-free engine modules into ``plugin_dir/engine_shared``."""
    here = Path(__file__).resolve().parent
    dest = Path(plugin_dir) / SHARED_PACKAGE
    dest.mkdir(parents=True, exist_ok=True)
    (dest / "__init__.py").write_text('"""Copies of ssn_engine modules made by ssn-shadow install-plugin."""\n')
    for name in SHARED_MODULES:
        shutil.copy2(here / name, dest / name)
    return dest


def engine_config(python: str | None = None) -> dict:
    """The command that starts the engine worker."""
    from . import __version__

    return {"python": python or sys.executable, "args": ["-m", "ssn_engine", "serve"], "version": __version__}


def write_engine_config(plugin_dir: Path, python: str | None = None) -> Path:
    """Write ``engine.json`` (which Python runs the worker) into the plug-in folder."""
    path = Path(plugin_dir) / CONFIG_NAME
    path.write_text(json.dumps(engine_config(python), indent=2) + "\n")
    return path
