"""Writing one mesh's views as a checkpoint directory, atomically (write to a temporary name, rename).

Layout of ``DIR/views/<uid>/`` (V views, N pixels, T = Hb * 2Hb texels):
  mask.npy         (V, N, N) float16   coverage in [0, 1]
  ao.npy           (V, N, N) float16   A^(1/3)
  occ_spans.npy    (V, T, N, 2) uint16 row spans, see :mod:`training.data.spans`
  occ_data.npy     (K,) uint8          occ * 255 inside the spans, all views concatenated
  occ_offsets.npy  (V + 1,) int64      where each view's data starts in occ_data
  info.json        mesh record, per-view records, render seconds (written last)
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from . import spans as spanlib

VIEWS = "views"
INFO = "info.json"


def mesh_dir(root: Path, uid: str) -> Path:
    return Path(root) / VIEWS / uid


def is_done(root: Path, uid: str) -> bool:
    """A mesh is finished when its directory holds info.json (renamed into place last)."""
    return (mesh_dir(root, uid) / INFO).is_file()


def write_mesh(
    root: Path, uid: str, masks: list[np.ndarray], aos: list[np.ndarray], occs: list[np.ndarray], info: dict
) -> int:
    """Write the views of one mesh; returns the bytes written. ``occs`` are (T, N, N) uint8."""
    final = mesh_dir(root, uid)
    tmp = final.parent / f".tmp-{uid}-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    packed = [spanlib.pack(o) for o in occs]
    offsets = np.zeros(len(occs) + 1, np.int64)
    offsets[1:] = np.cumsum([d.size for _, d in packed])
    np.save(tmp / "mask.npy", np.stack(masks).astype(np.float16))
    np.save(tmp / "ao.npy", np.stack(aos).astype(np.float16))
    np.save(tmp / "occ_spans.npy", np.stack([s for s, _ in packed]))
    np.save(tmp / "occ_data.npy", np.concatenate([d for _, d in packed]))
    np.save(tmp / "occ_offsets.npy", offsets)
    (tmp / INFO).write_text(json.dumps(info, indent=1))
    if final.exists():
        shutil.rmtree(final)
    os.replace(tmp, final)
    return sum(p.stat().st_size for p in final.iterdir())


def remove_stale(root: Path) -> None:
    """Delete temporary directories that interrupted runs left behind."""
    views = Path(root) / VIEWS
    if views.is_dir():
        for p in views.glob(".tmp-*"):
            shutil.rmtree(p, ignore_errors=True)
