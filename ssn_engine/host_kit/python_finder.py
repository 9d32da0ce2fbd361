"""Find a Python 3.10+ with ``venv`` to make the engine's environment from (stdlib only; the plug-ins carry a copy).

The host's own Python first (Krita and GIMP embed or use one), then those on
PATH, newest first, and on Windows the ``py`` launcher; each candidate is
asked what it is by running it.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from .setup_failures import SetupError

MIN_PYTHON = (3, 10)
PROBE = (
    "import json, sys, importlib.util as u; print(json.dumps({'executable': sys.executable, "
    "'version': list(sys.version_info[:3]), 'venv': u.find_spec('venv') is not None, "
    "'ensurepip': u.find_spec('ensurepip') is not None}))"
)


def no_window() -> dict:
    """Keep Windows from opening a console for each child process."""
    if sys.platform.startswith("win"):
        return {"creationflags": getattr(subprocess, "CREATE_NO_WINDOW", 0)}
    return {}


@dataclass(frozen=True)
class PythonFound:
    """A usable Python: its executable, version, and whether it has ``ensurepip`` (else pip comes from the index)."""

    executable: str
    version: tuple[int, ...]
    ensurepip: bool


def python_candidates(
    platform: str | None = None,
    executable: str | None = None,
    base_prefix: str | None = None,
    version: Sequence[int] | None = None,
    which: Callable[[str], str | None] = shutil.which,
) -> list[list[str]]:
    """Commands that may start a Python, best first: the host's own (its ``sys.executable`` when that is a Python,
    else the interpreter in its ``sys.base_prefix``: Krita and GIMP embed one), then those on PATH, newest first."""
    platform = platform or sys.platform
    executable = sys.executable if executable is None else executable
    base_prefix = sys.base_prefix if base_prefix is None else base_prefix
    major, minor = tuple(version or sys.version_info[:2])[:2]
    found: list[list[str]] = []
    windows = platform.startswith("win")
    if executable and Path(executable).name.lower().startswith("python"):
        found.append([executable])
    if base_prefix:
        base = Path(base_prefix)
        own = [base / "python.exe"] if windows else [base / "bin" / f"python{major}.{minor}", base / "bin" / "python3"]
        found += [[str(p)] for p in own]
    names = [f"python3.{m}" for m in range(14, MIN_PYTHON[1] - 1, -1)] + ["python3", "python"]
    for name in names:
        path = which(name)
        if path:
            found.append([path])
    if windows and which("py"):
        found.append([str(which("py")), "-3"])
    unique: list[list[str]] = []
    for command in found:
        if command not in unique:
            unique.append(command)
    return unique


def probe_python(command: Sequence[str], timeout: float = 30.0) -> PythonFound | None:
    """Ask a candidate what it is; None if it does not start or has no ``venv`` module."""
    try:
        out = subprocess.run(
            [*command, "-I", "-c", PROBE], capture_output=True, text=True, timeout=timeout, **no_window()
        )
        info = json.loads(out.stdout.strip().splitlines()[-1])
    except (OSError, subprocess.SubprocessError, ValueError, IndexError):
        return None
    if out.returncode != 0 or not info.get("venv"):
        return None
    return PythonFound(str(info["executable"]), tuple(int(v) for v in info["version"]), bool(info["ensurepip"]))


def install_python_hint(platform: str | None = None) -> str:
    """What to install, in words, for this system."""
    platform = platform or sys.platform
    if platform.startswith("win"):
        return "Install Python 3.10 or newer from https://www.python.org/downloads/ (tick 'Add python.exe to PATH')"
    if platform == "darwin":
        return "Install Python 3.10 or newer from https://www.python.org/downloads/ (or 'brew install python')"
    return "Install Python 3.10 or newer with its venv module (Debian/Ubuntu: 'sudo apt install python3 python3-venv')"


def find_python(
    candidates: Sequence[Sequence[str]], probe: Callable[[Sequence[str]], PythonFound | None] = probe_python
) -> PythonFound:
    """The first candidate that is a Python 3.10+ with ``venv`` (one with ``ensurepip`` preferred)."""
    usable, too_old = [], []
    for command in candidates:
        found = probe(command)
        if found is None:
            continue
        (usable if found.version[:2] >= MIN_PYTHON else too_old).append(found)
    with_pip = [p for p in usable if p.ensurepip]
    if with_pip or usable:
        return (with_pip or usable)[0]
    if too_old:
        old = ", ".join(f"{p.executable} ({'.'.join(map(str, p.version))})" for p in too_old)
        raise SetupError(
            f"The engine needs Python 3.10 or newer; found only {old}. {install_python_hint()}, then "
            "press Set up again."
        )
    raise SetupError(f"No Python with its venv module was found. {install_python_hint()}, then press Set up again.")
