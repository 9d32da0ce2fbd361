"""An in-memory stand-in for training.data.store.ViewStore (same interface), and checks of it.

Other training tests import :class:`FakeStore` from here.
"""

from __future__ import annotations

import numpy as np

from ssn_engine.hemisphere import soft_shadow, texel_weights


class _View:
    def __init__(self, mask, ao, occlusion, info):
        self.mask, self.ao, self.occlusion, self.info = mask, ao, occlusion, info


class FakeStore:
    """``n_meshes`` boxes x ``views`` views, frame N = ``res``, basis grid Hb x 2Hb; occlusion is a blurred
    shifted copy of the mask per texel (enough structure for shapes, algebra and a few training steps)."""

    def __init__(self, res: int = 32, elm_rows: int = 4, n_meshes: int = 6, views: int = 2, seed: int = 0):
        self.meta = {"res": res, "elm_rows": elm_rows, "samples_per_texel": 4, "format": "stand-in"}
        rng = np.random.default_rng(seed)
        splits = ["train", "train", "train", "val", "test", "test"]
        kinds = ["object", "human", "animal", "object", "object", "human"]
        self._views = []
        for m in range(n_meshes):
            for k in range(views):
                mask = np.zeros((res, res), np.float32)
                w, h = rng.integers(res // 8, res // 3), rng.integers(res // 4, res // 2)
                c = res // 2 + int(rng.integers(-2, 3))
                mask[2 : 2 + h, c - w // 2 : c + w // 2 + 1] = 1.0
                occ = np.zeros((elm_rows, 2 * elm_rows, res, res), np.uint8)
                for i in range(elm_rows):
                    for j in range(2 * elm_rows):
                        dy, dx = 1 + (elm_rows - i), (j - elm_rows)
                        occ[i, j] = np.roll(np.roll(mask, dy, 0), dx // 2, 1) * 255 * (0.5 + 0.5 * i / elm_rows)
                ao = np.clip(1.0 - occ.mean(axis=(0, 1)) / 255.0, 0, 1) ** (1 / 3)
                info = {
                    "split": splits[m % len(splits)],
                    "kind": kinds[m % len(kinds)],
                    "category": "box",
                    "source": "fake",
                    "mesh_id": f"fake_{m:02d}",
                    "yaw": float(45 * k),
                    "pitch": float(15 * k),
                    "fov": 45.0,
                    "focal": res / 2 / np.tan(np.radians(22.5)),
                    "shift": -0.1 * res,
                }
                self._views.append(_View(mask, ao.astype(np.float32), occ, info))
        self.meshes = [
            {
                "mesh": {
                    "id": f"fake_{m:02d}",
                    "split": splits[m % len(splits)],
                    "kind": kinds[m % len(kinds)],
                    "source": "fake",
                    "params": {},
                }
            }
            for m in range(n_meshes)
        ]
        self._weights = texel_weights(elm_rows)

    def __len__(self) -> int:
        return len(self._views)

    def view_ids(self, split="train", kind=None):
        return [
            i
            for i, v in enumerate(self._views)
            if (split is None or v.info["split"] == split) and (kind is None or v.info["kind"] == kind)
        ]

    def info(self, i):
        return dict(self._views[i].info)

    def load(self, i, with_occ=True):
        return self._views[i]

    def shadow(self, occlusion, elm):
        return soft_shadow(np.asarray(occlusion, np.float32) / np.float32(255), elm)

    def irradiance(self, occlusion, elm):
        w = (np.asarray(elm, np.float64) * self._weights).reshape(-1)
        occ = np.asarray(occlusion).reshape(w.size, -1).astype(np.float32)
        e = w.sum() - (w.astype(np.float32) / np.float32(255)) @ occ
        return np.maximum(e, 0.0).astype(np.float32).reshape(occlusion.shape[2:])

    def shadow_batch(self, occlusion, elms):
        return np.stack([self.shadow(o, e) for o, e in zip(occlusion, elms, strict=True)])


def tiny_run_args(resolution: int, warmup: int, *extra: str) -> list[str]:
    """`training.train` arguments of a tiny run on the stand-in store: a 4-8-8 U-Net, batches of 4, one thread."""
    return [
        "--resolution",
        str(resolution),
        "--widths",
        "4,8,8",
        "--groups",
        "2",
        "--batch",
        "4",
        "--val-samples",
        "4",
        "--val-every",
        "2",
        "--threads",
        "1",
        "--warmup",
        str(warmup),
        *extra,
    ]


def test_standin_shapes_and_splits():
    s = FakeStore()
    v = s.load(s.view_ids("train")[0])
    assert v.mask.shape == (32, 32) and v.ao.shape == (32, 32)
    assert v.occlusion.shape == (4, 8, 32, 32) and v.occlusion.dtype == np.uint8
    assert s.view_ids("test", "human") and s.view_ids("val")


def test_standin_shadow_and_irradiance_agree():
    s = FakeStore()
    v = s.load(0)
    elm = np.random.default_rng(1).random((4, 8)).astype(np.float32)
    sh = s.shadow(v.occlusion, elm)
    e = s.irradiance(v.occlusion, elm)
    e0 = float((elm * texel_weights(4)).sum())
    np.testing.assert_allclose(sh, 1 - e / e0, atol=1e-5)
