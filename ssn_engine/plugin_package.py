"""One file per host that an artist installs without a terminal (``ssn-shadow package krita|gimp --out FILE``).

The archive holds the plug-in as the host's installer lays it out (Krita: the
``.desktop`` file and the ``ssn_shadow`` folder, for Tools > Scripts > Import
Python Plugin from File; GIMP: the ``ssn-shadow`` folder to unpack into the
plug-ins folder), the host kit, ``setup.json`` and the engine's wheel (the
model inside it), or only the exact requirement for the package index. The
plug-in's **Set up** (:mod:`ssn_engine.host_kit.engine_setup`) installs that.

Built reproducibly: the wheel with ``SOURCE_DATE_EPOCH`` fixed, the archive's
entries sorted, dated 1980-01-01 and with fixed permissions, so the same
source gives the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from types import ModuleType

from . import __version__
from .host_kit.engine_setup import SETUP_NAME

SOURCE_ROOT = Path(__file__).resolve().parents[1]
SOURCE_DATE_EPOCH = "315532800"  # 1980-01-01, the earliest date a zip entry can hold
ZIP_DATE = (1980, 1, 1, 0, 0, 0)


class PackageError(RuntimeError):
    """The package cannot be built; the message says why."""


SOURCES = ("pyproject.toml", "README.md", "ssn_engine", "plugin_krita", "plugin_gimp")
PLUGIN_FOLDERS = ("ssn_shadow", "ssn-shadow")


def _not_sources(folder: str, names: list[str]) -> set[str]:
    """What a development tree holds beside the sources: caches, and what ``install-plugin --link`` generated in
    the plug-in folders (their host-kit link, engine.json)."""
    generated = {"host_kit", "engine.json", "worker.json"} if Path(folder).name in PLUGIN_FOLDERS else set()
    return {n for n in names if n == "__pycache__" or n.endswith(".pyc") or n in generated}


def build_wheel(out_dir: Path, source: Path = SOURCE_ROOT) -> Path:
    """The engine's wheel built from a clean copy of a source checkout's sources (no stale build folder, nothing a
    development install generated), reproducibly."""
    if not (source / "pyproject.toml").is_file():
        raise PackageError(
            f"{source} is not a source checkout of ssn-shadow (no pyproject.toml): give --wheel or --requirement"
        )
    env = dict(os.environ, SOURCE_DATE_EPOCH=SOURCE_DATE_EPOCH, PYTHONHASHSEED="0")
    with tempfile.TemporaryDirectory() as build:
        tree = Path(build) / "src"
        for name in SOURCES:
            if (source / name).is_dir():
                shutil.copytree(source / name, tree / name, ignore=_not_sources)
            else:
                tree.mkdir(exist_ok=True)
                shutil.copy2(source / name, tree / name)
        cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", build]
        proc = subprocess.run([*cmd, str(tree)], capture_output=True, text=True, env=env, cwd=build)
        if proc.returncode != 0:
            raise PackageError(f"building the wheel failed:\n{proc.stdout}{proc.stderr}")
        (wheel,) = Path(build).glob("ssn_shadow-*.whl")
        out_dir.mkdir(parents=True, exist_ok=True)
        return Path(wheel.replace(out_dir / wheel.name))


def write_setup(plugin_dir: Path, wheel: Path | None, requirement: str | None) -> Path:
    """Put the wheel (or the requirement) and ``setup.json`` into a staged plug-in folder."""
    if wheel is not None:
        data = wheel.read_bytes()
        (plugin_dir / wheel.name).write_bytes(data)
        setup = {"version": __version__, "wheel": wheel.name, "sha256": hashlib.sha256(data).hexdigest()}
    else:
        setup = {"version": __version__, "requirement": requirement or f"ssn-shadow=={__version__}"}
    path = plugin_dir / SETUP_NAME
    path.write_text(json.dumps(setup, indent=2) + "\n")
    return path


def write_archive(root: Path, out: Path) -> Path:
    """Zip everything under ``root`` (folders as entries too: Krita's importer looks for them) reproducibly."""
    tmp = out.with_name(out.name + ".part")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as zf:
        for path in sorted(root.rglob("*")):
            if "__pycache__" in path.parts or path.suffix == ".pyc":
                continue
            name = path.relative_to(root).as_posix() + ("/" if path.is_dir() else "")
            info = zipfile.ZipInfo(name, ZIP_DATE)
            if path.is_dir():
                info.external_attr = (0o40755 << 16) | 0x10
                zf.writestr(info, b"")
            else:
                info.external_attr = (0o100755 if os.access(path, os.X_OK) else 0o100644) << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                zf.writestr(info, path.read_bytes(), compresslevel=9)
    return Path(tmp.replace(out))


def package(host_install: ModuleType, out: Path, wheel: Path | None = None, requirement: str | None = None) -> Path:
    """Build the host's one-file package at ``out``: ``host_install`` is the host's installer module (its
    ``stage(root)`` lays the plug-in out under ``root``); the engine is ``wheel``, else ``requirement``, else a
    wheel built from this source checkout."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "root"
        plugin_dir = host_install.stage(root)
        if wheel is None and requirement is None:
            wheel = build_wheel(Path(tmp) / "wheel")
        elif wheel is not None and not Path(wheel).is_file():
            raise PackageError(f"no such wheel: {wheel}")
        write_setup(plugin_dir, Path(wheel) if wheel is not None else None, requirement)
        return write_archive(root, out)
