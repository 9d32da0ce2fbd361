"""Choose the output floors of a model on the validation split: its raw shadows (floor 0) floored afterwards with
each (broad, small-lights) pair as ``onnx_ssn.floor_for`` blends them, on the same views and light maps, by family.

usage: PYTHONPATH=. python tools/floor_sweep.py [--model DIR] [--views 90] [--pairs 0.01,0.01 0.004,0.02 ...]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ssn_engine.methods import OnnxSSN
from ssn_engine.methods.onnx_ssn import apply_floor, floor_for, small_lights_share
from training.data.store import ViewStore
from training.evaluate_families import KINDS, family_lights
from training.metrics import all_metrics, sun_geometry

FAMILIES = ("sun", "two", "sky", "table1")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", default="ssn_engine/models")
    p.add_argument("--data", default="data/ssn256")
    p.add_argument("--split", default="val")
    p.add_argument("--views", type=int, default=90)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--pairs", nargs="+", default=["0.01,0.01", "0,0", "0.004,0.004", "0.004,0.02", "0.01,0.03"])
    args = p.parse_args(argv)
    pairs = [tuple(float(x) for x in pair.split(",")) for pair in args.pairs]
    store = ViewStore(args.data)
    rows_hb = store.meta["elm_rows"]
    model = OnnxSSN(args.model)
    model.output_floor = model.output_floor_small_lights = 0.0  # raw output; floored below
    ids = sorted(i for k in KINDS for i in store.view_ids(args.split, k))
    ids = [ids[int(j)] for j in np.linspace(0, len(ids) - 1, args.views).round()]
    scores: dict = {(f, pair): [] for f in FAMILIES for pair in pairs}
    geometry: dict = {pair: [] for pair in pairs}
    t0 = time.perf_counter()
    for j, i in enumerate(ids):
        view = store.load(i)
        ao = model.predict_ao(view.mask[None])
        for family in FAMILIES:
            elm_hb, elm16 = family_lights(args.seed, j, family, 1, rows_hb)
            truth = store.shadow(view.occlusion, elm_hb[0])
            raw = model.render(view.mask[None], ao, elm16)[0]
            share = small_lights_share(elm16)
            for pair in pairs:
                s = apply_floor(raw, float(floor_for(share, *pair)[0]))
                scores[family, pair].append(all_metrics(s, truth))
                if family == "sun":
                    geometry[pair].append(sun_geometry(s, truth, view.mask))
    print(
        f"{len(ids)} {args.split} views, one light map per family (seed {args.seed}), {time.perf_counter() - t0:.0f} s"
    )
    print("| floor (broad, small lights) | " + " | ".join(FAMILIES) + " | sun direction error, length ratio |")
    print("|---|" + "---|" * (len(FAMILIES) + 1))
    for pair in pairs:
        means = [{k: np.mean([r[k] for r in scores[f, pair]]) for k in ("ZNCC", "DSSIM")} for f in FAMILIES]
        cells = [f"{m['ZNCC']:.4f} / {m['DSSIM']:.4f}" for m in means]
        sun = [g for g in geometry[pair] if g]
        angle = np.median([g["direction_error"] for g in sun]) if sun else float("nan")
        ratio = np.median([g["length_ratio"] for g in sun]) if sun else float("nan")
        print(f"| {pair[0]}, {pair[1]} | " + " | ".join(cells) + f" | {angle:.1f}, {ratio:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
