"""A dependency-free progress bar that also reads well in a log file."""

from __future__ import annotations

import sys
import time


class Progress:
    """Counts finished units (meshes) and views; prints one line per update."""

    def __init__(self, total: int, stream=sys.stderr):
        self.total, self.done, self.views = total, 0, 0
        self.start = time.time()
        self.stream = stream
        self.tty = stream.isatty()

    def update(self, views: int, label: str = "") -> None:
        self.done += 1
        self.views += views
        elapsed = time.time() - self.start
        rate = elapsed / self.views if self.views else 0.0
        eta = (self.total - self.done) * (elapsed / self.done)
        width = 30
        bar = "#" * int(width * self.done / max(self.total, 1))
        line = (f"[{bar:<{width}}] {self.done}/{self.total} meshes, {self.views} views, "
                f"{rate:.2f} s/view, elapsed {_hms(elapsed)}, eta {_hms(eta)} {label}")
        self.stream.write(("\r" + line) if self.tty else line + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")


def _hms(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 3600}h{s % 3600 // 60:02d}m{s % 60:02d}s"
