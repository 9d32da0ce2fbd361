"""A dependency-free progress bar for training loops."""

from __future__ import annotations

import sys
import time


class Progress:
    """``[####      ] step/total  rate  eta  message`` on one line (a new line per update when not a terminal)."""

    def __init__(self, total: int, start: int = 0, every: int = 10, stream=None):
        self.total, self.start, self.every = total, start, every
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def line(self, step: int, message: str = "") -> str:
        frac = min(1.0, step / max(1, self.total))
        done = int(30 * frac)
        elapsed = time.perf_counter() - self.t0
        rate = (step - self.start) / elapsed if elapsed > 0 else 0.0
        eta = (self.total - step) / rate if rate > 0 else float("nan")
        eta_s = "?" if eta != eta else f"{int(eta // 3600)}h{int(eta % 3600 // 60):02d}m{int(eta % 60):02d}s"
        return f"[{'#' * done}{' ' * (30 - done)}] {step}/{self.total} {rate:.2f} it/s eta {eta_s} {message}"

    def update(self, step: int, message: str = "") -> None:
        if step % self.every and step != self.total:
            return
        text = self.line(step, message)
        if self.tty:
            self.stream.write("\r" + text)
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()
