"""A contact sheet PNG: per view, the mask, the AO map and soft shadows under a few fixed ELMs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ssn_engine.hemisphere import render_light_map
from ssn_engine.light_map import LightMap

from .store import ViewStore


def sheet_elms(hb: int) -> list[np.ndarray]:
    """Three ELMs: a small light right of centre, a light ahead (behind the object), a broad sky."""
    maps = []
    for lights in ([(0.65, 0.55, 0.002, 1.0)], [(0.5, 0.75, 0.004, 1.0)],
                   [(0.3, 0.3, 0.05, 1.0), (0.8, 0.6, 0.01, 1.0)]):
        lm = LightMap()
        for u, v, soft, inten in lights:
            lm.add(u, v, soft, inten)
        maps.append(render_light_map(lm, hb))
    return maps


def pick_views(store: ViewStore, count: int) -> list[int]:
    """Up to ``count`` views from different meshes, spread over the store."""
    per_mesh = len(store) // max(len(store.meshes), 1) or 1
    mesh_step = max(1, len(store.meshes) // count)
    ids = [m * per_mesh + (m // mesh_step) % per_mesh for m in range(0, len(store.meshes), mesh_step)]
    return [i for i in ids if i < len(store)][:count]


def write_contact_sheet(root: Path, count: int = 8, tile: int = 128, path: Path | None = None) -> Path:
    """Rows of [mask | AO | shadow x 3]; shadows drawn dark on white. Returns the PNG path."""
    store = ViewStore(root)
    elms = sheet_elms(store.meta["elm_rows"])
    rows = []
    for i in pick_views(store, count):
        v = store.load(i)
        tiles = [1.0 - v.mask, v.ao] + [1.0 - store.shadow(v.occlusion, e) * (1 - 0.5 * v.mask) for e in elms]
        imgs = [Image.fromarray((np.clip(t, 0, 1) * 255).astype(np.uint8)).resize((tile, tile), Image.BILINEAR)
                for t in tiles]
        rows.append(np.concatenate([np.pad(np.asarray(im), 1, constant_values=128) for im in imgs], axis=1))
    path = Path(path or Path(root) / "contact_sheet.png")
    if rows:
        Image.fromarray(np.concatenate(rows, axis=0)).save(path, optimize=True)
    return path
