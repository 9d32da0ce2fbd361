"""Set up the shadow engine from inside a host: a private Python environment in the user's data folder.

Standard library only (both plug-ins carry a copy). A packaged plug-in
(``ssn-shadow package``) carries ``setup.json`` and the engine's wheel; when
no engine is configured the host offers **Set up**, which runs
:class:`EngineSetup` off the UI thread: find a Python 3.10+ (the host's own
first), create ``<data>/engine`` with ``venv``, give it pip (from the
package index where the Python has no ``ensurepip``), ``pip install`` the
wheel and its dependencies, check that the engine imports, and last write
``engine/setup-done.json``. That marker, written only after everything
succeeded, is what makes the environment count: a killed or failed set-up
leaves none, and the next one resumes (the environment and pip's cache in
``<data>/cache`` are reused). A plug-in carrying another wheel than the
marker names (an update) asks to set up again, which upgrades in place.

Every failure ends in :class:`SetupError` with a message that says what to
do; the whole log is ``<data>/setup.log``.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import urllib.parse
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from .python_finder import PythonFound, find_python, no_window, probe_python, python_candidates
from .setup_failures import SetupCancelled, SetupError, explain_failure, index_reachable, index_url, url_opener


SETUP_NAME = "setup.json"  # beside a packaged plug-in: what Set up installs
DATA_ENV = "SSN_SHADOW_DATA"  # overrides the data folder (tests, administrators)
DONE_NAME = "setup-done.json"  # inside the environment, written last
READY = "The shadow engine {version} is set up."
PIP_LINK = r'href="([^"]*?/?(pip-(\d+(?:\.\d+)*)-py3-none-any\.whl)(?:#sha256=([0-9a-f]+))?)"'  # simple API
Report = Callable[[float, str], None]


# -- where things are ------------------------------------------------------------------------------------------------
def data_dir(platform: str | None = None, env: Mapping[str, str] | None = None, home: Path | None = None) -> Path:
    """The engine's folder in the user's data: ``$SSN_SHADOW_DATA``, else ~/.local/share/ssn-shadow (Linux,
    ``$XDG_DATA_HOME``), %LOCALAPPDATA%\\ssn-shadow (Windows), ~/Library/Application Support/ssn-shadow (macOS)."""
    platform = platform or sys.platform
    env = os.environ if env is None else env
    home = home or Path.home()
    if env.get(DATA_ENV):
        return Path(env[DATA_ENV])
    if platform.startswith("win"):
        base = Path(env["LOCALAPPDATA"]) if env.get("LOCALAPPDATA") else home / "AppData" / "Local"
        return base / "ssn-shadow"
    if platform == "darwin":
        return home / "Library" / "Application Support" / "ssn-shadow"
    base = Path(env["XDG_DATA_HOME"]) if env.get("XDG_DATA_HOME") else home / ".local" / "share"
    return base / "ssn-shadow"


def env_python(env_dir: Path, platform: str | None = None) -> Path:
    """The Python inside a virtual environment."""
    platform = platform or sys.platform
    if platform.startswith("win"):
        return Path(env_dir) / "Scripts" / "python.exe"
    return Path(env_dir) / "bin" / "python"


@dataclass(frozen=True)
class Bundle:
    """What a packaged plug-in installs: its engine wheel (or a requirement for the package index)."""

    version: str
    wheel: Path | None = None
    sha256: str = ""
    requirement: str = ""

    @property
    def target(self) -> str:
        """What ``pip install`` is given."""
        return str(self.wheel) if self.wheel is not None else self.requirement

    @property
    def identity(self) -> str:
        """What the done-marker records: the wheel's hash, or the requirement."""
        return self.sha256 or self.requirement


def read_bundle(plugin_dir: Path) -> Bundle | None:
    """The plug-in's ``setup.json``; None for a plug-in installed with ``ssn-shadow install-plugin``."""
    path = Path(plugin_dir) / SETUP_NAME
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        version = str(data["version"])
        if data.get("wheel"):
            return Bundle(version, Path(plugin_dir) / str(data["wheel"]), str(data["sha256"]))
        return Bundle(version, requirement=str(data["requirement"]))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SetupError(f"{path} is damaged ({exc}); import the plug-in's file again.") from None


# -- state -------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class State:
    """Whether the environment in ``data`` serves ``bundle``: ``ready``, ``missing`` or ``outdated``."""

    status: str
    python: Path
    installed_version: str = ""

    def describe(self, bundle: Bundle) -> str:
        """What the host says of an engine not ready for ``bundle``: what Set up (or Update) will do."""
        if self.status == "outdated":
            return (
                f"The plug-in was updated ({self.installed_version} -> {bundle.version}): press Update to update "
                "its engine (the dependencies it has are kept)."
            )
        return (
            "The shadow engine is not set up yet. Set up installs it into a folder of its own: about 105 MB "
            "downloaded from the Python package index, 450 MB on disk; a minute or a few, by your connection."
        )


def engine_state(bundle: Bundle, data: Path) -> State:
    """Read ``data/engine``'s done-marker against the plug-in's bundle."""
    env_dir = Path(data) / "engine"
    python = env_python(env_dir)
    try:
        done = json.loads((env_dir / DONE_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return State("missing", python)
    if not isinstance(done, dict) or not python.exists():
        return State("missing", python)
    if done.get("identity") != bundle.identity:
        return State("outdated", python, str(done.get("version", "?")))
    return State("ready", python, str(done.get("version", "")))


def package_named(line: str) -> str:
    """The package a line of ``pip install`` starts on ("Collecting numpy>=1.24", "Processing /x/numpy-2.4-...whl",
    "Requirement already satisfied: numpy in ..."), or ""."""
    if line.startswith("Collecting "):
        return line.split()[1]
    if line.startswith("Processing "):
        return Path(line.split(None, 1)[1]).name.split("-")[0]
    if line.startswith("Requirement already satisfied:"):
        return line.split(":", 1)[1].split()[0]
    return ""


# -- the set-up ------------------------------------------------------------------------------------------------------
class EngineSetup:
    """One set-up run: ``run(report, cancelled)`` from a worker thread (:class:`SetupJob`)."""

    def __init__(
        self,
        bundle: Bundle,
        data: Path,
        candidates: Sequence[Sequence[str]] | None = None,
        env: Mapping[str, str] | None = None,
    ) -> None:
        self.bundle, self.data = bundle, Path(data)
        self.candidates = python_candidates() if candidates is None else candidates
        self.env = dict(os.environ if env is None else env)
        self.env_dir = self.data / "engine"
        self.python = env_python(self.env_dir)
        self.log_path = self.data / "setup.log"
        self._cancelled = threading.Event()

    # -- steps -----------------------------------------------------------------
    def run(self, report: Report, cancelled: threading.Event | None = None) -> Path:
        """Set up (or update, or resume); returns the environment's Python. Raises SetupError."""
        self._cancelled = cancelled or threading.Event()
        try:
            self.data.mkdir(parents=True, exist_ok=True)
            (self.data / "cache").mkdir(exist_ok=True)
            with open(self.log_path, "a", encoding="utf-8") as log:
                log.write(f"\n=== set-up of ssn-shadow {self.bundle.version} at {time.strftime('%Y-%m-%d %H:%M:%S')}\n")
        except OSError as exc:
            raise SetupError(explain_failure(str(exc), self.data, self.env, "Creating the folder")) from None
        (self.env_dir / DONE_NAME).unlink(missing_ok=True)
        report(0.0, "Looking for Python 3.10 or newer...")
        found = find_python(self.candidates)
        self.log(f"python: {found.executable} {'.'.join(map(str, found.version))}")
        self._check_cancel()
        report(0.04, f"Creating the engine's environment with Python {'.'.join(map(str, found.version[:2]))}...")
        self._make_environment(found)
        report(0.1, "Getting pip...")
        self._ensure_pip()
        self._install(report, 0.12, 0.93)
        report(0.94, "Checking the engine...")
        version = (
            self._step(
                [str(self.python), "-I", "-c", "import onnxruntime, ssn_engine; print(ssn_engine.__version__)"],
                "Checking the engine",
            )
            .strip()
            .splitlines()[-1]
        )
        if version != self.bundle.version:
            raise SetupError(f"The environment holds engine {version}, not {self.bundle.version}; press Set up again.")
        done = {"version": version, "identity": self.bundle.identity, "python": str(found.executable)}
        tmp = self.env_dir / (DONE_NAME + ".tmp")
        tmp.write_text(json.dumps(done, indent=2) + "\n", encoding="utf-8")
        os.replace(tmp, self.env_dir / DONE_NAME)
        self.log("done")
        report(1.0, READY.format(version=version))
        return self.python

    def _make_environment(self, found: PythonFound) -> None:
        """Reuse a working environment of this Python's version (a resumed or updated set-up), else make it anew."""
        if self.python.exists():
            ok = probe_python([str(self.python)])
            if ok is not None and ok.version[:2] == found.version[:2]:
                self.log("reusing the environment")
                return
            self.log("the environment is broken or of another Python: made anew")
        if self.env_dir.exists():
            shutil.rmtree(self.env_dir, ignore_errors=True)
        args = [found.executable, "-m", "venv", *([] if found.ensurepip else ["--without-pip"]), str(self.env_dir)]
        self._step(args, "Creating the environment")

    def _ensure_pip(self) -> None:
        """pip in the environment: there from ``ensurepip``, else its wheel from the package index."""
        try:
            self._step([str(self.python), "-m", "pip", "--version"], "Checking pip", quiet=True)
            return
        except SetupError:
            pass
        wheel = self._download_pip()
        self._step([str(self.python), f"{wheel}/pip", "install", "--no-index", str(wheel)], "Installing pip")

    def _download_pip(self) -> Path:
        """The newest ``pip-*-py3-none-any.whl`` of the index's simple page, checked against its sha256."""
        index = index_url(self.env).rstrip("/")
        try:
            opener = url_opener(self.env)
            with opener.open(f"{index}/pip/", timeout=60) as page:
                html = page.read().decode("utf-8", "replace")
            links = re.findall(PIP_LINK, html)
            if not links:
                raise SetupError(f"The package index {index} lists no pip wheel.")
            url, name, _, sha = max(links, key=lambda link: tuple(int(p) for p in link[2].split(".")))
            dest = self.data / "cache" / name
            with opener.open(urllib.parse.urljoin(f"{index}/pip/", url), timeout=120) as response:
                body = response.read()
        except SetupError:
            raise
        except Exception as exc:  # urllib's errors: no network, proxy, TLS
            self.log(f"pip download: {exc!r}")
            raise SetupError(explain_failure(repr(exc) + " NewConnectionError", self.data, self.env, "pip")) from None
        if sha and hashlib.sha256(body).hexdigest() != sha:
            raise SetupError(f"The pip wheel from {index} does not match its checksum; press Set up again.")
        dest.write_bytes(body)
        return dest

    def _install(self, report: Report, start: float, end: float) -> None:
        """``pip install`` the engine, its progress read from pip's lines (each package collected, then installed)."""
        args = [
            str(self.python), "-m", "pip", "install", "--upgrade", "--progress-bar", "off",
            "--disable-pip-version-check", "--no-input", self.bundle.target,
        ]  # fmt: skip
        collected = 0
        expected = 16  # the engine's dependency tree today; the bar only needs an estimate

        def on_line(line: str) -> None:
            nonlocal collected
            name = package_named(line)
            if name:
                collected += 1
                share = min(collected / expected, 1.0) * 0.7
                report(start + (end - start) * share, f"Getting {name}...")
            elif line.startswith("Installing collected packages"):
                report(start + (end - start) * 0.75, "Installing the downloaded packages...")

        report(start, f"Installing the engine {self.bundle.version} and its dependencies...")
        try:
            self._step(args, "Installing the engine", on_line=on_line)
        except SetupCancelled:
            raise
        except SetupError as exc:
            index = index_url(self.env)
            if "Cannot reach the package index" in str(exc) and index_reachable(index, self.env):
                missing = re.findall(r"No matching distribution found for (\S+)", self._tail())
                raise SetupError(
                    f"The package index {index} has no {missing[-1] if missing else 'such package'} for this Python "
                    f"and system. The log {self.log_path} names what is missing."
                ) from None
            raise
        if self.bundle.wheel is not None:  # a rebuilt wheel of the same version replaces the one installed
            self._step([*args[:4], "--force-reinstall", "--no-deps", *args[4:]], "Installing the engine")

    # -- processes -------------------------------------------------------------
    def _step(
        self, args: list[str], what: str, on_line: Callable[[str], None] | None = None, quiet: bool = False
    ) -> str:
        """Run one command, logging its output; a failure raises SetupError with what to do."""
        self._check_cancel()
        self.log("$ " + " ".join(args))
        env = {k: v for k, v in self.env.items() if k not in ("PYTHONHOME", "PYTHONPATH", "PYTHONSTARTUP")}
        env.update(PIP_CACHE_DIR=str(self.data / "cache"), PYTHONUNBUFFERED="1", PYTHONIOENCODING="utf-8")
        try:
            proc = subprocess.Popen(
                args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, cwd=self.data,
                text=True, encoding="utf-8", errors="replace", env=env, **no_window(),
            )  # fmt: skip
        except OSError as exc:
            raise SetupError(explain_failure(str(exc), self.data, self.env, what)) from None
        lines: list[str] = []
        watcher = threading.Thread(target=self._kill_on_cancel, args=(proc,), daemon=True)
        watcher.start()
        assert proc.stdout is not None
        with open(self.log_path, "a", encoding="utf-8") as log:
            for line in proc.stdout:
                log.write(line)
                lines.append(line)
                if on_line is not None:
                    on_line(line.strip())
        code = proc.wait()
        self._check_cancel()
        output = "".join(lines)
        if code != 0:
            if quiet:
                raise SetupError(output)
            raise SetupError(explain_failure(output, self.data, self.env, what))
        return output

    def _kill_on_cancel(self, proc: subprocess.Popen) -> None:
        while proc.poll() is None:
            if self._cancelled.wait(0.2):
                proc.kill()
                return

    def _check_cancel(self) -> None:
        if self._cancelled.is_set():
            self.log("cancelled")
            raise SetupCancelled("The set-up was cancelled; press Set up to resume it.")

    def _tail(self, size: int = 20000) -> str:
        try:
            return self.log_path.read_text(encoding="utf-8", errors="replace")[-size:]
        except OSError:
            return ""

    def log(self, text: str) -> None:
        """Append a line to the set-up's log (never failing the set-up for it)."""
        try:
            with open(self.log_path, "a", encoding="utf-8") as log:
                log.write(text + "\n")
        except OSError:
            pass


@dataclass
class SetupEvent:
    """What the UI shows: progress ``fraction`` and ``text``; ``done`` at the end, with ``error`` if it failed."""

    fraction: float
    text: str
    done: bool = False
    error: str = ""
    cancelled: bool = False


class SetupJob:
    """An :class:`EngineSetup` on a thread of its own; the UI polls :meth:`events` from its timer."""

    def __init__(self, setup: EngineSetup) -> None:
        self.setup = setup
        self._events: list[SetupEvent] = []
        self._lock = threading.Lock()
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="ssn-shadow set-up", daemon=True)

    def start(self) -> SetupJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    def events(self) -> list[SetupEvent]:
        """The events since the last call."""
        with self._lock:
            events, self._events = self._events, []
        return events

    def wait(self, timeout: float | None = None) -> None:
        self._thread.join(timeout)

    def _push(self, event: SetupEvent) -> None:
        with self._lock:
            self._events.append(event)

    def _run(self) -> None:
        try:
            self.setup.run(lambda f, t: self._push(SetupEvent(f, t)), self._cancel)
        except SetupCancelled as exc:
            self._push(SetupEvent(0.0, str(exc), done=True, error=str(exc), cancelled=True))
        except SetupError as exc:
            self._push(SetupEvent(0.0, str(exc), done=True, error=str(exc)))
        except OSError as exc:  # writing in the data folder: a full disk, a folder made read-only meanwhile
            message = explain_failure(str(exc), self.setup.data, self.setup.env, "Writing the engine's files")
            self._push(SetupEvent(0.0, message, done=True, error=message))
        except Exception as exc:  # never let a thread die silently: the panel must say it
            self.setup.log(f"unexpected: {exc!r}")
            self._push(SetupEvent(0.0, f"The set-up stopped: {exc}", done=True, error=str(exc)))
        else:
            self._push(SetupEvent(1.0, READY.format(version=self.setup.bundle.version), done=True))
