"""Render all views of one item and write its checkpoint directory."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from . import meshes, writer
from .items import Item, stable_hash
from .render_bases import render_view
from .sources import build_mesh
from .spans import quantise_counts
from .views import VIEWS, draw_view


def view_rng(seed: int, uid: str, k: int) -> np.random.Generator:
    """The generator of view k of item ``uid``: draws the camera (:func:`~.views.draw_view`), then the texel jitter."""
    return np.random.default_rng([seed, stable_hash(uid), k])


def render_item(
    item: Item, root: Path, res: int, elm_rows: int, samples: int, seed: int, cameras: str = "paper"
) -> dict:
    """Render the 15 views of ``item`` into ``root`` (cameras: :func:`draw_view`); returns a summary (views,
    seconds, bytes)."""
    t0 = time.perf_counter()
    mesh = build_mesh(item)
    topo = meshes.topology(mesh)
    masks, aos, occs, records = [], [], [], []
    for k in range(VIEWS):
        rng = view_rng(seed, item.id, k)
        yaw, pitch, fov = draw_view(k, rng, cameras)
        t = time.perf_counter()
        r = render_view(mesh, topo, yaw, pitch, fov, res, elm_rows, samples, rng)
        occs.append(quantise_counts(r.counts.reshape(-1, res, res), samples))
        masks.append(r.mask)
        aos.append(r.ao)
        records.append(
            {
                "yaw": yaw,
                "pitch": pitch,
                "fov": fov,
                "shift": float(r.camera.shift),
                "focal": float(r.camera.focal),
                "target_height": float(r.camera.target_height),
                "render_seconds": time.perf_counter() - t,
            }
        )
    seconds = time.perf_counter() - t0
    info = {
        "mesh": item.record() | {"vertices": int(len(mesh.vertices)), "faces": int(len(mesh.faces))},
        "views": records,
        "seconds": seconds,
        "res": res,
        "elm_rows": elm_rows,
        "samples": samples,
        "seed": seed,
        "cameras": cameras,
    }
    nbytes = writer.write_mesh(root, item.id, masks, aos, occs, info)
    return {"id": item.id, "views": len(records), "seconds": seconds, "bytes": nbytes}
