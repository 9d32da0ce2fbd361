"""A dataset's masks and AO maps at one resolution in one compressed file: what an AOP trains on, without the
shadow bases, small enough to travel to a GPU machine (its working tree is capped at 64 MiB; the bases are
gigabytes).

    python -m training.data.packed --data data/ssn256 data/ssn256c --res 128 --out .gpu/aop128.npz
    python -m training.train --module aop --data .gpu/aop128.npz --resolution 128 ...   # read as a store

:class:`PackedStore` has the interface of :class:`training.data.store.ViewStore` that an AOP's training uses;
its frame is the packed resolution, so each view's focal length and principal-point shift are rescaled to it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ssn_engine.frames import resample_frames

from .store import View, ViewStore

SCALED = ("focal", "shift")  # a view's camera entries in frame pixels


def is_packed(paths: list[str]) -> bool:
    """Whether a training run's ``--data`` names a packed file rather than dataset roots."""
    return len(paths) == 1 and paths[0].endswith(".npz")


class PackedStore:
    """The views of a :func:`pack` file: masks and AO maps (N, N) float32 at the packed N, no bases."""

    def __init__(self, path: str | Path):
        with np.load(path) as data:
            self.meta: dict = json.loads(str(data["meta"]))
            self._infos: list[dict] = json.loads(str(data["infos"]))
            self._mask, self._ao = data["mask"], data["ao"]

    def __len__(self) -> int:
        return len(self._infos)

    def view_ids(self, split: str | None = "train", kind: str | None = None) -> list[int]:
        """Ids of the views of ``split`` (None for all), optionally of one kind."""
        return [
            i
            for i, info in enumerate(self._infos)
            if (split is None or info["split"] == split) and (kind is None or info["kind"] == kind)
        ]

    def info(self, i: int) -> dict:
        return dict(self._infos[i])

    def load(self, i: int, with_occ: bool = True) -> View:
        """Mask, AO and info of view ``i``; a packed store holds no bases, so ``with_occ`` must be False."""
        if with_occ:
            raise ValueError("a packed store holds masks and AO maps only: it trains an AOP, not an SR")
        n, hb = self.meta["res"], self.meta["elm_rows"]
        mask = self._mask[i].astype(np.float32) / 255
        ao = self._ao[i].astype(np.float32) / 255
        return View(mask, ao, np.zeros((0, 2 * hb, n, n), np.uint8), self.info(i))


def pack(store, res: int, out: Path) -> int:
    """Write every view of ``store`` (a ViewStore) at ``res`` x ``res`` to ``out`` (8-bit masks and AO maps, the
    views' infos with their camera rescaled to the packed frame); returns the number of views."""
    n = store.meta["res"]
    ids = store.view_ids(None)
    masks = np.empty((len(ids), res, res), np.uint8)
    aos = np.empty_like(masks)
    infos = []
    for j, i in enumerate(ids):
        v = store.load(i, with_occ=False)
        frames = resample_frames(np.stack([v.mask, v.ao]), res)
        masks[j], aos[j] = np.rint(np.clip(frames, 0.0, 1.0) * 255).astype(np.uint8)
        infos.append({**v.info, **{key: float(v.info[key]) * res / n for key in SCALED}})
    meta = {**store.meta, "res": res, "format": "packed masks and AO", "packed_from_res": n}
    np.savez_compressed(out, mask=masks, ao=aos, infos=json.dumps(infos), meta=json.dumps(meta))
    return len(ids)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(prog="python -m training.data.packed", description=(__doc__ or "").split("\n")[0])
    p.add_argument("--data", nargs="+", required=True, help="dataset roots, read as one store")
    p.add_argument("--res", type=int, default=128, help="the packed frames' size (the AOP's training resolution)")
    p.add_argument("--out", type=Path, required=True, help="the .npz file to write")
    args = p.parse_args(argv)
    if args.out.suffix != ".npz":
        raise SystemExit(f"--out {args.out}: the packed file must end in .npz (training.train recognises it so)")
    count = pack(ViewStore(args.data), args.res, args.out)
    print(f"{count} views at {args.res} x {args.res} -> {args.out} ({args.out.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main()
