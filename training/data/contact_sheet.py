"""A contact sheet PNG: per view, the mask, the AO map and soft shadows under a few fixed ELMs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from ssn_engine.hemisphere import render_light_map
from ssn_engine.host_kit.light_map import LightMap

from .items import stable_hash
from .store import ViewStore


def sheet_elms(hb: int) -> list[np.ndarray]:
    """Three ELMs: a small light right of centre, a light ahead (behind the object), a broad sky."""
    maps = []
    for lights in (
        [(0.65, 0.55, 0.002, 1.0)],
        [(0.5, 0.75, 0.004, 1.0)],
        [(0.3, 0.3, 0.05, 1.0), (0.8, 0.6, 0.01, 1.0)],
    ):
        lm = LightMap()
        for u, v, soft, inten in lights:
            lm.add(u, v, soft, inten)
        maps.append(render_light_map(lm, hb))
    return maps


def pick_views(store: ViewStore, count: int) -> list[int]:
    """Up to ``count`` views of different meshes, in turn from each (source, kind) group (hash order)."""
    groups: dict[tuple[str, str], list[tuple[int, int]]] = {}
    first = 0
    for mesh in store.meshes:
        key = (mesh["mesh"]["source"], mesh["mesh"]["kind"])
        groups.setdefault(key, []).append((stable_hash(mesh["mesh"]["id"]), first))
        first += len(mesh["views"])
    lists = [[f for _, f in sorted(groups[k])] for k in sorted(groups)]
    picked: list[int] = []
    per_group = -(-count // max(len(lists), 1))
    for r in range(max((len(x) for x in lists), default=0)):
        for x in lists:
            if r < len(x) and len(picked) < count:
                step = max(1, len(x) // per_group)
                start = x[(r * step) % len(x)]
                picked.append(start + (3 * r + 1 + len(picked)) % 15)
    return picked


def write_contact_sheet(root: Path, count: int = 8, tile: int = 128, path: Path | None = None) -> Path:
    """Rows of [mask | AO | shadow x 3]; shadows drawn dark on white. Returns the PNG path."""
    store = ViewStore(root)
    elms = sheet_elms(store.meta["elm_rows"])
    rows = []
    for i in pick_views(store, count):
        v = store.load(i)
        tiles = [1.0 - v.mask, v.ao] + [1.0 - store.shadow(v.occlusion, e) * (1 - 0.5 * v.mask) for e in elms]
        imgs = [
            Image.fromarray((np.clip(t, 0, 1) * 255).astype(np.uint8)).resize((tile, tile), Image.Resampling.BILINEAR)
            for t in tiles
        ]
        rows.append(np.concatenate([np.pad(np.asarray(im), 1, constant_values=128) for im in imgs], axis=1))
    path = Path(path or Path(root) / "contact_sheet.png")
    if rows:
        Image.fromarray(np.concatenate(rows, axis=0)).save(path, optimize=True)
    return path
