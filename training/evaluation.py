"""The paper's Section 6 benchmark on checkpoints (``python -m training.evaluate``): every test view under random
Table 1 light maps, the geometric card, Non-inv-SSN, SSN and GT-AO-SSN, metrics by group and pitch, the tables.

On the test split, objects (object + animal) and humans separately, every view is paired with ``--per-view`` ELMs
from a fixed pool of ``--n-elms`` random Table 1 light maps (seeded). Rows: the engine's geometric card baseline,
Non-inv-SSN (SR trained on raw irradiance, converted to s = 1 - E / E0), SSN (AOP -> SR), GT-AO-SSN (ground-truth
AO into SR). Metrics on s at the dataset's resolution N; networks at R see frames resampled N -> R -> N as in the
engine.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from ssn_engine.frames import resample_frames
from ssn_engine.hemisphere import network_elm
from ssn_engine.methods.geometric import GeometricCard
from ssn_engine.methods.onnx_ssn import apply_floor

from .batches import irradiance_to_shadow, view_key
from .checkpoint import load_models
from .data.store import ViewStore
from .data.views import pitch_groups
from .elm import render_lights, sample_lights
from .metrics import NAMES, all_metrics, mean_metrics
from .model import MirrorAverage
from .plots import image_grid
from .progress import Progress

GROUPS = {"objects": ("object", "animal"), "humans": ("human",)}
PAPER = {
    "objects": {
        "Non-inv-SSN": (0.0926, 0.0894, 0.7521, 0.2913),
        "SSN": (0.0561, 0.0506, 0.8192, 0.0616),
        "GT-AO-SSN": (0.0342, 0.0304, 0.9171, 0.0461),
    },
    "humans": {"SSN": (0.0194, 0.0163, 0.8943, 0.0467), "GT-AO-SSN": (0.0150, 0.0127, 0.9316, 0.0403)},
}


def elm_pool(n: int, seed: int, elm_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """The fixed ELM pool on the dataset's grid and on the network's 16 x 32 grid."""
    lights = sample_lights(np.random.default_rng([seed, 1]), n)
    return render_lights(lights, elm_rows), render_lights(lights, 16)


def pick_views(ids: list[int], max_views: int) -> list[int]:
    if not max_views or len(ids) <= max_views:
        return list(ids)
    return [ids[int(j)] for j in np.linspace(0, len(ids) - 1, max_views).round()]


class Networks:
    """AOP and SR (and optionally Non-inv SR) checkpoints, run at their resolution R on N x N frames."""

    def __init__(self, aop: list[str], sr: str, noninv: str | None, floor: float = 0.0, mirror_average: bool = False):
        def load(paths: list[str]):
            net, cks = load_models(paths)
            return (MirrorAverage(net) if mirror_average else net), cks

        self.floor = floor
        self.aop, cks = load(aop)
        self.sr, (ck_sr,) = load([sr])
        self.noninv = load([noninv])[0] if noninv else None
        self.r = cks[0]["unet"]["resolution"]
        self.info = {
            "aop": [{"path": p, "step": ck["step"], "samples": ck["samples"]} for p, ck in zip(aop, cks, strict=True)],
            "sr": {"path": sr, "step": ck_sr["step"], "samples": ck_sr["samples"]},
            "mirror_average": mirror_average,
        }

    @torch.no_grad()
    def predict_ao(self, masks: np.ndarray) -> np.ndarray:
        n = masks.shape[-1]
        m = torch.from_numpy(resample_frames(masks, self.r)[:, None])
        ao = self.aop(m)[:, 0].clamp(0, 1).numpy()
        return np.clip(resample_frames(ao, n), 0, 1)

    @torch.no_grad()
    def render(
        self,
        masks: np.ndarray,
        ao: np.ndarray,
        elm16: np.ndarray,
        elm_hb: np.ndarray | None = None,
        noninv: bool = False,
    ) -> np.ndarray:
        n = masks.shape[-1]
        m = torch.from_numpy(resample_frames(masks, self.r)[:, None])
        a = torch.from_numpy(resample_frames(ao, self.r)[:, None])
        e = torch.from_numpy(network_elm(elm16))
        net = self.noninv if noninv else self.sr
        if net is None or (noninv and elm_hb is None):
            raise ValueError("a Non-inv-SSN render needs its checkpoint (--noninv) and the basis-grid light maps")
        out = net(m, a, e)[:, 0].numpy()
        if elm_hb is not None and noninv:
            out = irradiance_to_shadow(resample_frames(out, n), elm_hb, elm16)
        else:
            out = resample_frames(np.clip(out, 0, 1), n)
        return apply_floor(out, self.floor).astype(np.float32)


def evaluate(args: argparse.Namespace, store=None) -> dict:
    torch.set_num_threads(args.threads)
    store = store if store is not None else ViewStore(args.data)
    n_px, rows_hb = store.meta["res"], store.meta["elm_rows"]
    elm_hb, elm16 = elm_pool(args.n_elms, args.seed, rows_hb)
    nets = Networks(args.aop, args.sr, args.noninv, args.floor, args.mirror_average) if args.aop and args.sr else None
    geo = None if args.no_geometric else GeometricCard(resolution=n_px)
    methods = (["geometric"] if geo else []) + (["Non-inv-SSN"] if nets and nets.noninv else [])
    methods += ["SSN", "GT-AO-SSN"] if nets else []
    results: dict = {
        "methods": methods,
        "groups": {},
        "n_elms": args.n_elms,
        "per_view": args.per_view,
        "data": str(args.data),
        "N": n_px,
        "R": nets.r if nets else None,
        "split": args.split,
        "floor": args.floor,
        "networks": nets.info if nets else {},
    }
    cache_path = Path(args.geo_cache) if args.geo_cache else None
    geo_cache = dict(np.load(cache_path)) if cache_path and cache_path.is_file() else {}
    grid_rows = []
    failures = AOFailures() if nets else None
    t0 = time.perf_counter()
    for group, kinds in GROUPS.items():
        ids = [i for k in kinds for i in store.view_ids(args.split, k)]
        ids = pick_views(sorted(ids), args.max_views)
        per = {m: [] for m in methods}
        pitches: list[float] = []
        prog = Progress(len(ids), every=max(1, len(ids) // 10))
        for j, i in enumerate(ids):
            v = store.load(i)
            pick = [(j * args.per_view + k) % args.n_elms for k in range(args.per_view)]
            gt = np.stack([store.shadow(v.occlusion, elm_hb[q]) for q in pick])
            masks = np.repeat(v.mask[None], len(pick), 0)
            gt_ao = np.repeat(v.ao[None], len(pick), 0)
            preds = {}
            if geo:
                keys = ["|".join(map(str, (*view_key(store, i), args.seed, args.n_elms, q))) for q in pick]
                if all(k in geo_cache for k in keys):
                    preds["geometric"] = np.stack([geo_cache[k].astype(np.float32) for k in keys])
                else:
                    geo_ao = geo.predict_ao(masks[:1]).repeat(len(pick), 0)
                    preds["geometric"] = geo.render(masks, geo_ao, elm16[pick])
                    geo_cache.update({k: p.astype(np.float16) for k, p in zip(keys, preds["geometric"], strict=True)})
            if nets:
                ao_pred = nets.predict_ao(masks[:1]).repeat(len(pick), 0)
                if nets.noninv:
                    preds["Non-inv-SSN"] = nets.render(masks, ao_pred, elm16[pick], elm_hb[pick], noninv=True)
                preds["SSN"] = nets.render(masks, ao_pred, elm16[pick])
                preds["GT-AO-SSN"] = nets.render(masks, gt_ao, elm16[pick])
            for m in methods:
                per[m].extend(all_metrics(preds[m][b], gt[b]) for b in range(len(pick)))
            pitches += [float(store.info(i).get("pitch", 0.0))] * len(pick)
            if failures:
                gap = [per["SSN"][-k]["DSSIM"] - per["GT-AO-SSN"][-k]["DSSIM"] for k in range(len(pick), 0, -1)]
                b = int(np.argmax(gap))
                failures.offer(gap[b], [v.mask, v.ao, ao_pred[b], gt[b], preds["SSN"][b], preds["GT-AO-SSN"][b]])
            if j % max(1, len(ids) // 3) == 0 and len(grid_rows) < 6:
                elm_img = np.kron(elm16[pick[0]] / max(elm16[pick[0]].max(), 1e-9), np.ones((n_px // 32, n_px // 32)))
                elm_img = np.pad(elm_img, ((0, n_px - elm_img.shape[0]), (0, 0)))
                grid_rows.append([v.mask, elm_img, gt[0]] + [preds[m][0] for m in methods])
            prog.update(j + 1, group)
        prog.close()
        by_pitch = {}
        for q, rows in pitch_groups(pitches).items():
            by_pitch[q] = {
                "images": len(rows),
                "metrics": {m: mean_metrics([per[m][b] for b in rows]) for m in methods},
            }
        results["groups"][group] = {
            "views": len(ids),
            "images": len(ids) * args.per_view,
            "metrics": {m: mean_metrics(per[m]) for m in methods},
            "by_pitch": by_pitch,
        }
    results["seconds"] = time.perf_counter() - t0
    if cache_path:
        cache_path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(cache_path, **geo_cache)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    (out / "tables.md").write_text(tables_markdown(results))
    if grid_rows:
        image_grid(grid_rows, out / "grid.png", ["mask", "ELM", "ground truth"] + methods, cell=128)
    if failures and failures.rows:
        image_grid(failures.images(), out / "ao_failures.png", list(AOFailures.COLUMNS), cell=128)
    return results


class AOFailures:
    """The images where the predicted AO costs most: largest DSSIM of SSN minus that of GT-AO-SSN."""

    COLUMNS = ("mask", "ground-truth AO", "predicted AO", "ground truth", "SSN", "GT-AO-SSN")

    def __init__(self, keep: int = 6):
        self.keep = keep
        self.rows: list[tuple[float, list[np.ndarray]]] = []

    def offer(self, gap: float, images: list[np.ndarray]) -> None:
        self.rows.append((gap, [np.asarray(x, np.float32) for x in images]))
        self.rows = sorted(self.rows, key=lambda r: -r[0])[: self.keep]

    def images(self) -> list[list[np.ndarray]]:
        return [r[1] for r in self.rows]


def pitch_table(results: dict) -> list[str]:
    """ZNCC and DSSIM per camera pitch (the views' pitch, 0, 15 or 30 degrees, or its range: ``pitch_groups``)."""
    methods = results["methods"]
    lines = [
        "### By camera pitch (ZNCC / DSSIM)\n",
        "| group | pitch | images | " + " | ".join(methods) + " |",
        "|---" * (3 + len(methods)) + "|",
    ]
    for group, r in results["groups"].items():
        for q, row in r.get("by_pitch", {}).items():
            cells = " | ".join(f"{row['metrics'][m]['ZNCC']:.3f} / {row['metrics'][m]['DSSIM']:.3f}" for m in methods)
            lines.append(f"| {group} | {q} | {row['images']} | {cells} |")
    return lines + [""]


def tables_markdown(results: dict) -> str:
    """Our tables beside the paper's Tables 1 (objects) and 2 (humans)."""
    lines = []
    for group, r in results["groups"].items():
        lines.append(
            f"### {group.capitalize()} ({r['views']} {results['split']} views x {results['per_view']} ELMs"
            f" = {r['images']} images)\n"
        )
        lines.append("| Method | " + " | ".join(NAMES) + " | paper " + " | paper ".join(NAMES) + " |")
        lines.append("|---" * (1 + 2 * len(NAMES)) + "|")
        for m in results["methods"]:
            ours = " | ".join(f"{r['metrics'][m][k]:.4f}" for k in NAMES)
            paper = PAPER.get(group, {}).get(m)
            theirs = " | ".join(f"{x:.4f}" for x in paper) if paper else " | ".join("-" for _ in NAMES)
            lines.append(f"| {m} | {ours} | {theirs} |")
        lines.append("")
    return "\n".join(lines + pitch_table(results))
