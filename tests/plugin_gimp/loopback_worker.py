"""A host engine worker on a loopback port for the chroot's GIMP (the integration test and
tools/gimp_window_figure.py): GIMP in the chroot reaches it through engine.json's address and token."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def loopback_worker(repo: Path) -> Iterator[tuple[int, str]]:
    """``python -m ssn_engine serve --port 0`` run from ``repo``: yields (port, token); killed on exit."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "ssn_engine", "serve", "--port", "0"],
        cwd=repo,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None and proc.stderr is not None  # both PIPE
        line = proc.stdout.readline()
        if not line.startswith("listening 127.0.0.1:"):
            raise RuntimeError(f"worker said {line!r}; stderr: {proc.stderr.read()[-2000:]}")
        _, address, token = line.split()
        yield int(address.rsplit(":", 1)[1]), token.removeprefix("token=")
    finally:
        proc.kill()
        proc.wait(timeout=10)
