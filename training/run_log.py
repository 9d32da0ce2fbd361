"""A run's log: ``log.csv`` (appended on resume), the progress bar, the loss plot, and the clocks of a run."""

from __future__ import annotations

import csv
import time
from pathlib import Path

from .plots import loss_curve
from .progress import Progress

__all__ = ["LOG_FIELDS", "Interval", "RunLog", "plot_log", "read_log"]


LOG_FIELDS = ["step", "samples", "lr", "train_loss", "val_loss", "seconds", "samples_per_s"]


def read_log(path: Path) -> list[dict]:
    if not path.is_file():
        return []
    with path.open() as f:
        return list(csv.DictReader(f))


def plot_log(run: Path, title: str) -> None:
    rows = read_log(run / "log.csv")
    train = [(float(r["step"]), float(r["train_loss"])) for r in rows if r["train_loss"]]
    val = [(float(r["step"]), float(r["val_loss"])) for r in rows if r["val_loss"]]
    loss_curve({"train": train, "val": val}, run / "loss.png", title)


class Interval:
    """A clock that is due every ``minutes`` after its last restart."""

    def __init__(self, minutes: float):
        self.seconds = minutes * 60
        self.restart()

    def restart(self) -> None:
        self.t0 = time.perf_counter()

    def due(self) -> bool:
        return time.perf_counter() - self.t0 > self.seconds


class RunLog:
    """``log.csv`` (rank 0; appended on resume, its seconds counted on from the last row), the progress bar and
    the running mean of the train loss between two rows."""

    def __init__(self, run: Path, is_main: bool, steps: int, step: int, every: int, samples_per_step: int):
        path = run / "log.csv"
        new = not path.is_file()
        self.is_main, self.samples_per_step = is_main, samples_per_step
        self.file = path.open("a", newline="") if is_main else None
        self.writer = csv.DictWriter(self.file, LOG_FIELDS) if self.file else None
        if self.writer and new:
            self.writer.writeheader()
        self.t_start = time.perf_counter()
        old_rows = read_log(path) if is_main and not new else []
        self.prior_seconds = float(old_rows[-1]["seconds"]) if old_rows else 0.0
        self.progress = Progress(steps, start=step, every=every)
        self.running, self.n_running, self.t_log = 0.0, 0, time.perf_counter()

    def elapsed(self) -> float:
        """Seconds since this chunk of the run started."""
        return time.perf_counter() - self.t_start

    def add(self, step: int, loss: float, lr: float) -> None:
        self.running += loss
        self.n_running += 1
        if self.is_main:
            self.progress.update(step, f"loss {self.running / self.n_running:.5f} lr {lr:.2e}")

    def row(self, step: int, samples: int, lr: float) -> dict:
        """The next row (no validation loss yet); restarts the running mean."""
        row = {
            "step": step,
            "samples": samples,
            "lr": f"{lr:.3e}",
            "train_loss": f"{self.running / self.n_running:.6f}",
            "val_loss": "",
            "seconds": f"{self.prior_seconds + self.elapsed():.1f}",
            "samples_per_s": f"{self.n_running * self.samples_per_step / (time.perf_counter() - self.t_log):.2f}",
        }
        self.running, self.n_running, self.t_log = 0.0, 0, time.perf_counter()
        return row

    def write(self, row: dict) -> None:
        """Append ``row`` to log.csv (rank 0 only: the other ranks keep no log)."""
        if self.writer is None or self.file is None:
            raise RuntimeError("only rank 0 writes the run's log")
        self.writer.writerow(row)
        self.file.flush()

    def close(self) -> None:
        if self.file:
            self.file.close()
