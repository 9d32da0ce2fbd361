"""Install the GIMP 3 plug-in into a user's GIMP profile (used by ``ssn-shadow install-plugin gimp``).

The plug-in folder ``ssn-shadow/`` is copied (or its files symlinked, for
development) into GIMP's user plug-ins folder, gets copies of the engine's
toolkit-free modules (``host_kit/``) and an ``engine.json`` that says how
to reach the engine: the Python that runs ``python -m ssn_engine serve``, or,
with ``address``, a worker already listening on a loopback port (``ssn-shadow
serve --port N``), e.g. for a GIMP that runs in a chroot or container.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from collections.abc import Mapping
from pathlib import Path

from ssn_engine.plugin_files import CONFIG_NAME, KIT_PACKAGE, copy_host_kit, write_engine_config

PLUGIN_NAME = "ssn-shadow"
SOURCE_DIR = Path(__file__).resolve().parent / PLUGIN_NAME
GIMP_SERIES = "3.0"


def gimp_profile_dir(
    platform: str | None = None, env: Mapping[str, str] | None = None, home: Path | None = None
) -> Path:
    """The user's GIMP 3 profile folder (``GIMP3_DIRECTORY`` overrides it, as in GIMP)."""
    platform = platform or sys.platform
    env = os.environ if env is None else env
    home = home or Path.home()
    if env.get("GIMP3_DIRECTORY"):
        return Path(env["GIMP3_DIRECTORY"])
    if platform.startswith("win"):
        base = Path(env["APPDATA"]) if env.get("APPDATA") else home / "AppData" / "Roaming"
        return base / "GIMP" / GIMP_SERIES
    if platform == "darwin":
        return home / "Library" / "Application Support" / "GIMP" / GIMP_SERIES
    base = Path(env["XDG_CONFIG_HOME"]) if env.get("XDG_CONFIG_HOME") else home / ".config"
    return base / "GIMP" / GIMP_SERIES


def default_dest(platform: str | None = None, env: Mapping[str, str] | None = None, home: Path | None = None) -> Path:
    """``<profile>/plug-ins/ssn-shadow``, e.g. ~/.config/GIMP/3.0/plug-ins/ssn-shadow on Linux."""
    return gimp_profile_dir(platform, env, home) / "plug-ins" / PLUGIN_NAME


def plugin_files(source: Path = SOURCE_DIR) -> list[Path]:
    """The plug-in's own files: the entry script and the modules beside it."""
    return sorted(p for p in source.iterdir() if p.is_file() and p.suffix == ".py")


def _clear(dest: Path) -> None:
    """Remove what a previous install put in ``dest`` (our files only)."""
    if dest.is_symlink():
        dest.unlink()
        return
    if not dest.exists():
        return
    ours = {p.name for p in plugin_files()} | {CONFIG_NAME, "worker.json"}  # worker.json: the shared worker
    for child in dest.iterdir():
        if child.name in ours or child.name == "__pycache__":
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
    shared = dest / KIT_PACKAGE
    if shared.is_symlink():
        shared.unlink()
    elif shared.is_dir():
        shutil.rmtree(shared)


def write_address_config(plugin_dir: Path, host: str, port: int, token: str) -> Path:
    """``engine.json`` pointing at a worker listening on ``host:port`` that printed ``token`` when it started."""
    from ssn_engine import __version__

    path = Path(plugin_dir) / CONFIG_NAME
    config = {"address": [host, int(port)], "token": token, "version": __version__}
    path.write_text(json.dumps(config, indent=2) + "\n")
    return path


def install(
    dest: Path | None = None,
    python: str | None = None,
    link: bool = False,
    *,
    address: tuple[str, int] | None = None,
    token: str = "",
    configure: bool = True,
) -> Path:
    """Install the plug-in; return its folder.

    Parameters
    ----------
    dest : the plug-in folder to create (its name should stay ``ssn-shadow``:
        GIMP runs ``<folder>/<folder>.py``); default :func:`default_dest`.
    python : the Python that runs the engine worker; default this one.
    link : symlink the plug-in's files instead of copying them (development).
    address : instead of spawning a worker, connect to one listening on this
        loopback ``(host, port)``.
    token : with ``address``, the token that worker printed when it started
        (``listening HOST:PORT token=TOKEN``).
    configure : write ``engine.json``; a package's plug-in sets up its own engine.
    """
    dest = Path(dest) if dest is not None else default_dest()
    if dest.name != PLUGIN_NAME:
        print(
            f"warning: GIMP only runs a plug-in whose folder is named like its script; {dest.name!r} "
            f"is not {PLUGIN_NAME!r}",
            file=sys.stderr,
        )
    _clear(dest)
    dest.mkdir(parents=True, exist_ok=True)
    for source in plugin_files():
        target = dest / (f"{dest.name}.py" if source.name == f"{PLUGIN_NAME}.py" else source.name)
        if link:
            target.symlink_to(source)
        else:
            shutil.copy2(source, target)
            if source.name == f"{PLUGIN_NAME}.py":
                target.chmod(0o755)
    copy_host_kit(dest, link)
    if address is not None:
        write_address_config(dest, *address, token)
    elif configure:
        write_engine_config(dest, python)
    return dest


def stage(root: Path) -> Path:
    """The plug-in as its package holds it (the ``ssn-shadow`` folder to unpack into GIMP's plug-ins folder), with
    no engine.json (the package's Set up makes the engine); returns the plug-in folder."""
    return install(Path(root) / PLUGIN_NAME, configure=False)
