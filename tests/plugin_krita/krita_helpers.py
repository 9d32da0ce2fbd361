"""Shared helpers of the plug-in tests: waiting on the Qt event loop, a stand-in Krita host."""

import dataclasses
import json
import os
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from PyQt5.QtCore import QEventLoop, QTimer

from plugin_krita.ssn_shadow.adapters.krita_document import Source, SourceError, WriteResult
from plugin_krita.ssn_shadow.adapters.pixel_format import pixel_format
from ssn_engine.host_kit import camera_rules
from ssn_engine.host_kit.engine_config import EngineConfig

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
IN_CI = os.environ.get("CI") == "true"


def need(tool: str) -> str:
    """The tool's path; outside CI a missing tool skips the test."""
    path = shutil.which(tool)
    if path is None:
        if IN_CI:
            pytest.fail(f"{tool} is missing in CI (.ci/run installs it)")
        pytest.skip(f"{tool} not installed")
    return path


def run_kritarunner(
    pykrita: Path,
    module: str,
    function: str,
    result: Path,
    env_extra: dict[str, str],
    screen: str = "",
    with_repo: bool = True,
    timeout_s: float = 300,
) -> dict:
    """Run ``function`` of the driver ``module`` (in this folder) in a fresh Krita (kritarunner) on a virtual X
    server (``screen``: its size, e.g. "1366x768x24"; else xvfb-run's), with the plug-in installed in
    ``pykrita`` (and ``with_repo``, this checkout on the path); returns the JSON the driver wrote to ``result``.

    Needs Debian's krita (kritarunner) and xvfb-run: Krita's undo action exists only with a window, which
    kritarunner can open on an X server but not on the offscreen platform.
    """
    kritarunner = need("kritarunner")
    xvfb = need("xvfb-run")
    env = dict(os.environ)
    env.update(
        env_extra,
        SSN_TEST_RESULT=str(result),
        # the plug-in as installed, the driver, and the repo (so the worker's Python finds ssn_engine)
        PYTHONPATH=os.pathsep.join([str(pykrita), str(HERE), *([str(REPO)] if with_repo else [])]),
        XDG_RUNTIME_DIR=str(result.parent),
    )
    env.pop("SSN_SHADOW_ENGINE_CONFIG", None)
    # Krita's embedded Python finds its home through the first python3 on PATH: make it Debian's,
    # not the test's (pyenv, venv, /usr/local), or it cannot import PyQt5/PyKrita.
    env["PATH"] = os.pathsep.join(["/usr/bin", "/bin", env.get("PATH", "")])
    env.pop("QT_QPA_PLATFORM", None)  # xcb on the virtual X server (the unit tests set offscreen)
    # kritarunner's exit status says nothing (and it may crash on exit): the result file counts. xvfb-run -a
    # checks only this /tmp's lock files, so an X server elsewhere (the GIMP test's chroot shares the abstract
    # socket namespace) can hold the display it picks ("could not connect to display"): start the search at a
    # random number, and retry.
    for _attempt in range(3):
        proc = subprocess.run(
            [
                xvfb,
                "-a",
                "-n",
                str(random.randint(200, 900)),
                *(["-s", f"-screen 0 {screen}"] if screen else []),
                kritarunner,
                "-s",
                module,
                "-f",
                function,
            ],
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout_s,
        )
        if result.exists() or "could not connect to display" not in proc.stderr:
            break
    assert result.exists(), f"Krita wrote no result\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    data = json.loads(result.read_text())
    assert "error" not in data, data["error"]
    assert data.get("done"), data
    return data


def run_in_fresh_profile(tmp_path: Path, module: str) -> dict:
    """Run ``main`` of the driver ``module`` in Krita with a fresh profile (under ``tmp_path``, the plug-in
    installed there) on a virtual 1366 x 768 screen (:func:`run_kritarunner`); OpenGL off, which the virtual X
    server cannot run (it changes no dock size)."""
    from plugin_krita.install import install

    pykrita = tmp_path / "pykrita"
    install(dest=pykrita, python=sys.executable)
    home = tmp_path / "home"
    (home / ".config").mkdir(parents=True)
    (home / ".config" / "kritadisplayrc").write_text("[General]\nOpenGLRenderer=none\n")
    env = {"HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config"), "XDG_DATA_HOME": str(home / "data")}
    return run_kritarunner(pykrita, module, "main", tmp_path / "result.json", env, "1366x768x24")


def worker_command(*args: str) -> EngineConfig:
    """The real engine worker from this checkout, or another Python command."""
    return EngineConfig((sys.executable, *(args or ("-m", "ssn_engine", "serve"))), env={"PYTHONPATH": str(REPO)})


def wait_until(predicate, timeout_s: float = 60.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            return False
        loop = QEventLoop()
        QTimer.singleShot(10, loop.quit)
        loop.exec_()
    return True


def cutout_alpha(w: int = 200, h: int = 160, box=(80, 40, 120, 140)) -> bytes:
    x0, y0, x1, y1 = box
    rows = []
    for y in range(h):
        inside = y0 <= y < y1
        rows.append(bytes(255 if inside and x0 <= x < x1 else 0 for x in range(w)))
    return b"".join(rows)


class FakeDocument:
    """Stands in for a Krita document: a file name, horizontal guides and annotations."""

    def __init__(self, name: str = "", guides=()):
        self.name, self.guides = name, list(guides)
        self.annotations: dict[str, tuple[str, bytes]] = {}


class FakeHost:
    """Stands in for Krita: a fixed source, and a record of the layer writes."""

    def __init__(self, alpha: bytes | None = None, w: int = 200, h: int = 160, fail: str | None = None):
        self.w, self.h = w, h
        self.alpha = alpha if alpha is not None else cutout_alpha(w, h)
        self.fail = fail
        self.writes: list[tuple] = []
        self.blends: list[str] = []
        self.reads = 0
        self.refreshes = 0  # the source read again (refresh_source)
        self.document = FakeDocument("a.kra")
        self.closed: list[FakeDocument] = []
        self.shadow: str | None = None  # the shadow layer's id on the "canvas"
        self.kept_active = 0
        self.takeovers: list[str] = []  # the shadow layer's ids given by begin_drag

    def active_document(self):
        return self.document

    def horizontal_guides(self, document):
        return list(document.guides) if document is not None else []

    def is_open(self, document):
        return document not in self.closed

    def annotation(self, document, kind):
        return document.annotations.get(kind, ("", b""))[1]

    def set_annotation(self, document, kind, description, data):
        document.annotations[kind] = (description, bytes(data))

    def read_source(self, document):
        self.reads += 1
        if self.fail:
            raise SourceError(self.fail)
        return Source(
            document,
            "node",
            "node-1",
            "Person",
            self.alpha,
            "uint8",
            self.w,
            self.h,
            False,
            pixel_format("RGBA", "U8"),
            "sRGB-elle-V2-srgbtrc.icc",
        )

    def refresh_source(self, source):
        """As Krita's adapter: the same source where the alpha is unchanged, else one with the new alpha."""
        self.refreshes += 1
        if self.fail:
            raise SourceError(self.fail)
        return source if source.alpha == self.alpha else dataclasses.replace(source, alpha=self.alpha)

    def write(self, source, pixels, rect, new_step, blend):
        self.writes.append((rect, len(pixels), new_step))
        self.pixels = pixels  # the last layer's
        self.blends.append(blend)
        if new_step or self.shadow is None:  # a new layer replaces the old one
            self.shadow = f"shadow-{len(self.writes)}"
        return WriteResult("shadow-node", new_step, "", self.shadow)

    def shadow_layer_id(self, source):
        return self.shadow

    def begin_drag(self, source, side):
        """As Krita's adapter: a shadow layer is replaced by a copy of itself (a new id), the drag's undo step."""
        if self.shadow is None:
            return self.preview_background(source, side), None
        self.shadow = f"shadow-copy-{len(self.takeovers)}"
        self.takeovers.append(self.shadow)
        return self.preview_background(source, side), WriteResult("shadow-node", True, "", self.shadow)

    def keep_source_active(self, source):
        self.kept_active += 1

    def preview_background(self, source, side):
        """A mid-grey image of the document's size scaled down as Krita's adapter scales it."""
        w, h, _ = camera_rules.preview_size(self.w, self.h, side)
        return w, h, bytes([128, 128, 128, 255]) * (w * h)
