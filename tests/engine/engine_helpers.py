"""Helpers shared by the engine tests (plain functions, no fixtures)."""

from __future__ import annotations

import functools
import io
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from ssn_engine.hemisphere import render_light_map  # noqa: E402
from ssn_engine.host_kit.light_map import LightMap  # noqa: E402
from ssn_engine.host_kit.protocol import read_message  # noqa: E402

if TYPE_CHECKING:
    from ssn_engine.worker import Worker

HELLO = b'{"id": 99, "cmd": "hello"}\n'  # sent last: its answer shows the worker still in step


@functools.lru_cache(maxsize=1)
def pawn() -> np.ndarray:
    """The bundled sample pawn (computed once per process; takes a few seconds)."""
    from ssn_engine.samples import pawn_cutout

    a = pawn_cutout()
    a.setflags(write=False)
    return a


def drawn_alpha(width: int = 160, height: int = 120, dtype=np.uint8) -> np.ndarray:
    """A small canvas with an upright rounded post standing near the bottom."""
    yy, xx = np.mgrid[0:height, 0:width]
    cx = width * 0.55
    body = (np.abs(xx - cx) < width * 0.08) & (yy > height * 0.25) & (yy < height * 0.85)
    head = (xx - cx) ** 2 + (yy - height * 0.25) ** 2 < (width * 0.1) ** 2
    inside = (body | head).astype(np.float64)
    if dtype == np.uint8:
        return (inside * 255).astype(np.uint8)
    if dtype == np.uint16:
        return (inside * 65535).astype(np.uint16)
    return inside.astype(dtype)


def one_light(u: float, v: float, softness: float = 0.002, intensity: float = 2.0) -> LightMap:
    lm = LightMap()
    lm.add(u, v, softness, intensity)
    return lm


def elm_for(u: float, v: float, softness: float = 0.002, intensity: float = 2.0) -> np.ndarray:
    """A (16, 32) ELM with one Gaussian light."""
    return render_light_map(one_light(u, v, softness, intensity))


def object_geometry(mask: np.ndarray, threshold: float = 0.5) -> tuple[int, int, float]:
    """(top row, base row, centre column) of a frame mask."""
    rows = np.flatnonzero(mask.max(axis=1) > threshold)
    cols = np.flatnonzero(mask.max(axis=0) > threshold)
    return int(rows[0]), int(rows[-1]), 0.5 * (cols[0] + cols[-1] + 1)


def shadow_centroid(shadow: np.ndarray, mask: np.ndarray) -> tuple[float, float, float]:
    """(mass, centre column, centre row) of the shadow on ground the object does not cover."""
    w = shadow * (1.0 - np.clip(mask, 0, 1))
    mass = float(w.sum())
    yy, xx = np.mgrid[0 : w.shape[0], 0 : w.shape[1]]
    if mass == 0:
        return 0.0, float("nan"), float("nan")
    return mass, float((w * (xx + 0.5)).sum() / mass), float((w * (yy + 0.5)).sum() / mass)


def engine_env(**extra: str) -> dict[str, str]:
    """Environment for engine subprocesses: the repo importable, no model override."""
    env = {k: v for k, v in os.environ.items() if k != "SSN_SHADOW_MODEL_DIR"}
    env["PYTHONPATH"] = str(REPO) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env.update(extra)
    return env


def pawn_scene(width: int, height: int, pawns: list[tuple[int, int, int]]) -> list[np.ndarray]:
    """The sample pawn's alpha (uint8) at several places on one ``width`` x ``height`` canvas, one alpha per pawn:
    ``pawns`` lists (pawn height, base row, centre column)."""
    from ssn_engine.samples import pawn_cutout

    out = []
    for size, base, centre in pawns:
        alpha = pawn_cutout((width, height), size, base)[..., 3]
        out.append(np.roll(alpha, centre - width // 2, axis=1))
    return out


def disc(width: int, height: int, cx: float, cy: float, r: float) -> np.ndarray:
    """A filled disc (uint8 alpha 255) on a ``width`` x ``height`` canvas."""
    yy, xx = np.mgrid[0:height, 0:width]
    return (((xx + 0.5 - cx) ** 2 + (yy + 0.5 - cy) ** 2 < r * r) * 255).astype(np.uint8)


def peak_alpha(shadow: np.ndarray, region: np.ndarray) -> float:
    """The peak of a shadow on a region of the canvas, robust to a few saturated contact pixels: its 95th
    percentile there."""
    return float(np.percentile(shadow[region], 95))


def converse(worker: Worker, data: bytes) -> tuple[list[dict], bool]:
    """Feed the byte stream ``data`` to ``worker`` in-process: its reply headers (each one's buffers read in full)
    and whether it was asked to shut down (serve's result)."""
    writer = io.BytesIO()
    ended = worker.serve(io.BytesIO(data), writer)
    writer.seek(0)
    replies = []
    while True:
        try:
            replies.append(read_message(writer)[0])
        except EOFError:
            return replies, ended


HUNG_WORKER = Path(__file__).resolve().parents[1] / "hung_worker.py"  # a worker that hangs (tests/hung_worker.py)


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, killed but not yet reaped by its parent, counts as stopped; a stopped
    process runs)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def gone_within(pid: int, seconds: float) -> bool:
    """Whether ``pid`` stops running within ``seconds``."""
    deadline = time.monotonic() + seconds
    while alive(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def wait_for_file(path: Path, seconds: float = 30.0) -> None:
    """Wait until ``path`` exists (asserting that it does within ``seconds``)."""
    deadline = time.monotonic() + seconds
    while not path.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert path.exists(), f"{path} never appeared"


def shared_render_call(command: list[str], state: Path) -> subprocess.Popen:
    """A call in a process of its own (as GIMP's plug-in is) that takes the shared worker run by ``command`` (its
    record at ``state``) and asks it to render."""
    caller = (
        "from pathlib import Path; from ssn_engine.host_kit import client; "
        "from ssn_engine.host_kit.engine_config import EngineConfig; "
        f"c = client.connect(EngineConfig(command=tuple({command!r}), shared=True), Path({str(state)!r})); "
        "c.request('render')"
    )
    return subprocess.Popen([sys.executable, "-c", caller])


class CancelAfter:
    """A client's ``on_wait`` hook: counts its calls and gives up ``delay`` seconds after the first (never, by
    default)."""

    def __init__(self, delay: float = float("inf")) -> None:
        self.delay, self.calls, self.cancelled_at = delay, 0, None
        self.first: float | None = None

    def __call__(self) -> bool:
        self.calls += 1
        now = time.monotonic()
        self.first = self.first or now
        if now - self.first >= self.delay:
            self.cancelled_at = self.cancelled_at or now
            return True
        return False
