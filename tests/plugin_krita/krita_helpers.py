"""Shared helpers of the plug-in tests: waiting on the Qt event loop, a stand-in Krita host."""

import sys
import time
from pathlib import Path

from PyQt5.QtCore import QEventLoop, QTimer

from plugin_krita.ssn_shadow.adapters.krita_document import Source, SourceError, WriteResult
from plugin_krita.ssn_shadow.adapters.pixel_format import pixel_format
from ssn_engine.host_kit import camera_rules
from ssn_engine.host_kit.engine_config import EngineConfig

REPO = Path(__file__).resolve().parents[2]


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
    """Stands in for a Krita document: a file name and horizontal guides."""

    def __init__(self, name: str = "", guides=()):
        self.name, self.guides = name, list(guides)

    def fileName(self):  # noqa: N802 (Krita's API)
        return self.name

    def horizontalGuides(self):  # noqa: N802 (Krita's API)
        return self.guides


class FakeHost:
    """Stands in for Krita: a fixed source, and a record of the layer writes."""

    def __init__(self, alpha: bytes | None = None, w: int = 200, h: int = 160, fail: str | None = None):
        self.w, self.h = w, h
        self.alpha = alpha if alpha is not None else cutout_alpha(w, h)
        self.fail = fail
        self.writes: list[tuple] = []
        self.blends: list[str] = []
        self.reads = 0
        self.document = FakeDocument("a.kra")

    def active_document(self):
        return self.document

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

    def write(self, source, pixels, rect, new_step, blend):
        self.writes.append((rect, len(pixels), new_step))
        self.blends.append(blend)
        return WriteResult("shadow-node", new_step)

    def preview_background(self, source, side):
        """A mid-grey image of the document's size scaled down as Krita's adapter scales it."""
        w, h, _ = camera_rules.preview_size(self.w, self.h, side)
        return w, h, bytes([128, 128, 128, 255]) * (w * h)
