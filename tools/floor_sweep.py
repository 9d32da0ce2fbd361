"""Choose the output floors and the AO gamma of a model on the validation split: its raw shadows (floor 0), with
the predicted AO map raised to each ``--ao-gammas`` power, floored afterwards with each (broad, small-lights)
pair as ``onnx_ssn.floor_for`` blends them, on the same views and light maps, by family.

usage: PYTHONPATH=. python tools/floor_sweep.py [--model DIR] [--views 90] [--pairs 0.01,0.01 0.004,0.02 ...]
    [--ao-gammas 1 0.6 ...]
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
    p.add_argument("--ao-gammas", nargs="+", type=float, default=None, help="default: the model's ao_gamma")
    args = p.parse_args(argv)
    pairs = [tuple(float(x) for x in pair.split(",")) for pair in args.pairs]
    store = ViewStore(args.data)
    rows_hb = store.meta["elm_rows"]
    model = OnnxSSN(args.model)
    model.output_floor = model.output_floor_small_lights = 0.0  # raw output; floored below
    gammas = args.ao_gammas or [model.ao_gamma]
    model.ao_gamma = 1.0  # the AOP's own map; raised below
    variants = [(pair, g) for g in gammas for pair in pairs]
    ids = sorted(i for k in KINDS for i in store.view_ids(args.split, k))
    ids = [ids[int(j)] for j in np.linspace(0, len(ids) - 1, args.views).round()]
    scores: dict = {(f, v): [] for f in FAMILIES for v in variants}
    geometry: dict = {v: [] for v in variants}
    t0 = time.perf_counter()
    for j, i in enumerate(ids):
        view = store.load(i)
        ao = model.predict_ao(view.mask[None])
        for family in FAMILIES:
            elm_hb, elm16 = family_lights(args.seed, j, family, 1, rows_hb)
            truth = store.shadow(view.occlusion, elm_hb[0])
            share = small_lights_share(elm16)
            for g in gammas:
                raw = model.render(view.mask[None], ao**g, elm16)[0]
                for pair in pairs:
                    s = apply_floor(raw, float(floor_for(share, *pair)[0]))
                    scores[family, (pair, g)].append(all_metrics(s, truth))
                    if family == "sun":
                        geometry[pair, g].append(sun_geometry(s, truth, view.mask))
    print(
        f"{len(ids)} {args.split} views, one light map per family (seed {args.seed}), {time.perf_counter() - t0:.0f} s"
    )
    head = " | ".join(FAMILIES)
    print(f"| floor (broad, small lights) | AO gamma | {head} | sun direction error, length ratio |")
    print("|---|---|" + "---|" * (len(FAMILIES) + 1))
    for v in variants:
        means = [{k: np.mean([r[k] for r in scores[f, v]]) for k in ("ZNCC", "DSSIM")} for f in FAMILIES]
        cells = [f"{m['ZNCC']:.4f} / {m['DSSIM']:.4f}" for m in means]
        sun = [g for g in geometry[v] if g]
        angle = np.median([g["direction_error"] for g in sun]) if sun else float("nan")
        ratio = np.median([g["length_ratio"] for g in sun]) if sun else float("nan")
        (broad, small), g = v
        print(f"| {broad}, {small} | {g:g} | " + " | ".join(cells) + f" | {angle:.1f}, {ratio:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
