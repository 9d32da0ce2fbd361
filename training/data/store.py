"""Reading a dataset written by ``python -m training.make_dataset`` (the training loop's interface).

>>> store = ViewStore("data/ssn256")
>>> v = store.load(store.view_ids("train")[0])
>>> s = store.shadow(v.occlusion, elm)        # elm (Hb, 2Hb), e.g. render_light_map(lm, Hb)

See ``training/data/README.md`` for the on-disk layout.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ssn_engine.hemisphere import soft_shadow, texel_weights

from . import spans as spanlib
from .writer import INFO, VIEWS

DATASET_JSON = "dataset.json"


@dataclass
class View:
    """One view: mask and AO (N, N) float32, occlusion (Hb, 2Hb, N, N) uint8 (occ * 255), info."""

    mask: np.ndarray
    ao: np.ndarray
    occlusion: np.ndarray
    info: dict


class ViewStore:
    """All finished meshes under ``root`` (every shard's output), as a flat list of views.

    View ids are positions in the list of (mesh uid, view index) sorted by uid,
    fixed for a given set of finished meshes (a store opened while generation
    still runs sees the meshes finished at that moment). Several roots (the same
    shapes at other cameras, say) are read as one store, root after root.
    """

    def __init__(self, root: str | Path | Sequence[str | Path]):
        roots = [Path(root)] if isinstance(root, (str, Path)) else [Path(r) for r in root]
        self.root = roots[0]
        self.meta: dict = json.loads((self.root / DATASET_JSON).read_text())
        self.meshes: list[dict] = []
        self._dirs: list[Path] = []
        self._views: list[tuple[int, int]] = []
        for other in roots[1:]:
            self._check_compatible(other)
        for r in roots:
            for d in sorted((r / VIEWS).iterdir()) if (r / VIEWS).is_dir() else []:
                if d.name.startswith(".") or not (d / INFO).is_file():
                    continue
                info = json.loads((d / INFO).read_text())
                m = len(self.meshes)
                self.meshes.append(info)
                self._dirs.append(d)
                self._views.extend((m, k) for k in range(len(info["views"])))
        self._arrays: dict[int, dict[str, np.ndarray]] = {}
        hb = self.meta["elm_rows"]
        self._weights = texel_weights(hb).astype(np.float64)

    def _check_compatible(self, root: Path) -> None:
        """Several roots are read as one store only if their views and bases have the same layout."""
        meta = json.loads((root / DATASET_JSON).read_text())
        for key in ("res", "elm_rows"):
            if meta[key] != self.meta[key]:
                raise ValueError(f"{root} has {key} {meta[key]}, {self.root} has {self.meta[key]}: not one store")

    def __len__(self) -> int:
        return len(self._views)

    def view_ids(self, split: str | None = "train", kind: str | None = None) -> list[int]:
        """Ids of the views of ``split`` ("train", "val", "test"; None for all), optionally of one kind."""
        out = []
        for i, (m, _) in enumerate(self._views):
            mesh = self.meshes[m]["mesh"]
            if (split is None or mesh["split"] == split) and (kind is None or mesh["kind"] == kind):
                out.append(i)
        return out

    def info(self, i: int) -> dict:
        """The info dict of view ``i`` without loading its arrays."""
        m, k = self._views[i]
        mesh = self.meshes[m]["mesh"]
        view = self.meshes[m]["views"][k]
        return {**{key: mesh[key] for key in ("split", "kind", "category", "source")}, "mesh_id": mesh["id"], **view}

    def _mesh_arrays(self, m: int) -> dict[str, np.ndarray]:
        arrays = self._arrays.get(m)
        if arrays is None:
            d = self._dirs[m]
            arrays = {
                name: np.load(d / f"{name}.npy", mmap_mode="r")
                for name in ("mask", "ao", "occ_spans", "occ_data", "occ_offsets")
            }
            self._arrays[m] = arrays
        return arrays

    def load(self, i: int, with_occ: bool = True) -> View:
        """Mask, AO, occlusion bases (``with_occ`` False: an empty array, for the AOP) and info of view ``i``."""
        m, k = self._views[i]
        a = self._mesh_arrays(m)
        n, hb = self.meta["res"], self.meta["elm_rows"]
        occ = np.zeros((0, 2 * hb, n, n), np.uint8)
        if with_occ:
            data = a["occ_data"][a["occ_offsets"][k] : a["occ_offsets"][k + 1]]
            occ = spanlib.unpack(np.asarray(a["occ_spans"][k]), data, n).reshape(hb, 2 * hb, n, n)
        return View(np.asarray(a["mask"][k], np.float32), np.asarray(a["ao"][k], np.float32), occ, self.info(i))

    def shadow(self, occlusion: np.ndarray, elm: np.ndarray) -> np.ndarray:
        """s = sum_t L_t W_t occ_t / sum_t L_t W_t via :func:`ssn_engine.hemisphere.soft_shadow`, (N, N)."""
        return soft_shadow(np.asarray(occlusion, np.float32) / np.float32(255), elm)

    def irradiance(self, occlusion: np.ndarray, elm: np.ndarray) -> np.ndarray:
        """E(x) = sum_t L_t W_t (1 - occ_t), (N, N) float32 (the Non-inverse ablation's target)."""
        w = (np.asarray(elm, np.float64) * self._weights).reshape(-1)
        occ = np.asarray(occlusion).reshape(w.size, -1)
        blocked = (w.astype(np.float32) / np.float32(255)) @ occ.astype(np.float32)
        e = w.sum() - blocked
        return np.maximum(e, 0.0).astype(np.float32).reshape(occlusion.shape[2:])

    def shadow_batch(self, occlusion: np.ndarray, elms: np.ndarray) -> np.ndarray:
        """Batched shadows: occlusion (B, Hb, 2Hb, N, N) uint8, elms (B, Hb, 2Hb) -> (B, N, N) float32."""
        b = occlusion.shape[0]
        w = np.asarray(elms, np.float64).reshape(b, -1) * self._weights.reshape(1, -1)
        total = w.sum(axis=1, keepdims=True)
        w = np.where(total > 0, w / np.where(total > 0, total, 1.0), 0.0) / 255.0
        occ = np.asarray(occlusion).reshape(b, w.shape[1], -1).astype(np.float32)
        s = np.matmul(w.astype(np.float32)[:, None, :], occ)[:, 0]
        return np.clip(s, 0.0, 1.0).reshape((b,) + occlusion.shape[-2:]).astype(np.float32)
