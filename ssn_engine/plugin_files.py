"""Files every host plug-in gets at install time.

The plug-ins run inside the host's own Python, which has no numpy, so they
carry a copy of the engine's stdlib-only package :mod:`ssn_engine.host_kit`
(the worker client and its protocol framing, the engine.json reader, the
light map, its editor and its picture, and every rule the hosts share).
``engine.json`` names the Python that runs ``ssn-shadow serve``.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

KIT_DIR = Path(__file__).resolve().parent / "host_kit"
KIT_PACKAGE = KIT_DIR.name  # the copy's name beside the plug-in: the same package, imported by that name
KIT_MODULES = tuple(sorted(p.name for p in KIT_DIR.glob("*.py")))
CONFIG_NAME = "engine.json"


def copy_host_kit(plugin_dir: Path, link: bool = False) -> Path:
    """Copy the host kit's modules into ``plugin_dir/host_kit`` (replacing an older copy), or with ``link`` (a
    development install) link that folder to the kit itself, so that it never falls behind the engine's; returns
    that folder."""
    dest = Path(plugin_dir) / KIT_PACKAGE
    if dest.is_symlink():
        dest.unlink()
    elif dest.is_dir():
        shutil.rmtree(dest)
    if link:
        dest.symlink_to(KIT_DIR, target_is_directory=True)
        return dest
    dest.mkdir(parents=True)
    for name in KIT_MODULES:
        shutil.copy2(KIT_DIR / name, dest / name)
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
