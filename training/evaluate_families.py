"""Evaluation by light family (``python -m training.evaluate --families [--model NAME=DIR ...]``).

Every test view is lit by ``--per-view`` light maps of each family of :mod:`training.elm` (``sun``: one small
light, ``two``: two small lights, ``sky``: 3 to 8 broad lights, ``table1``: the paper's sampling), drawn from a
generator seeded per view and family. Rows: the geometric card and each installed model folder (the engine's
ONNX graphs, exactly as ``predict_frames`` runs them), blind (no camera input: a model's camera estimator,
else the conventions' default camera) and, with ``--with-camera`` / ``--with-gt-ao``, given the view's true
camera input or its ground-truth AO. Metrics on s at the dataset's N (256 for the engine's frames) per family x
kind (object, human, animal) x pitch; for ``sun`` also the cast shadow's direction error and length ratio
(:func:`training.metrics.sun_geometry`).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from ssn_engine.hemisphere import render_light_map
from ssn_engine.host_kit.light_map import GaussianLight, LightMap
from ssn_engine.methods import GeometricCard, OnnxSSN

from .batches import camera_input
from .data.store import ViewStore
from .data.views import pitch_groups
from .elm import FAMILIES, render_lights, sample_family
from .metrics import NAMES, all_metrics, mean_metrics, sun_geometry
from .plots import image_grid
from .progress import Progress

KINDS = ("object", "human", "animal")
SUN_ELEVATIONS = (10.0, 25.0, 45.0, 70.0)  # the picture grid's suns, degrees
SUN_AZIMUTH_U = 0.8  # the grid's sun: right of the camera's forward direction, casting towards the viewer's left


class Row:
    """One evaluated configuration: a method, and whether it gets the true camera and the ground-truth AO."""

    def __init__(self, label: str, method, camera: bool = False, gt_ao: bool = False):
        self.label, self.method, self.camera, self.gt_ao = label, method, camera, gt_ao

    def ao(self, mask: np.ndarray, gt_ao: np.ndarray, cam: np.ndarray) -> np.ndarray:
        """The AO map (1, N, N) this row renders a view with: the ground truth, or the method's prediction."""
        return gt_ao[None] if self.gt_ao else self.method.predict_ao(mask[None], cam[None] if self.camera else None)

    def predict(self, mask: np.ndarray, ao: np.ndarray, elms: np.ndarray, cam: np.ndarray) -> np.ndarray:
        """Shadows (k, N, N) of one view under ``elms`` (k, 16, 32), with the AO of :meth:`ao`."""
        cameras = np.repeat(cam[None], len(elms), 0) if self.camera else None
        return self.method.render(np.repeat(mask[None], len(elms), 0), np.repeat(ao, len(elms), 0), elms, cameras)


def build_rows(args: argparse.Namespace, n: int) -> list[Row]:
    """The evaluated rows: the geometric card, each --model, and those given the camera or the ground-truth AO."""
    methods: dict[str, GeometricCard | OnnxSSN] = {"geometric": GeometricCard(resolution=n)}
    for spec in args.model:
        name, _, folder = spec.partition("=")
        if not folder:
            raise SystemExit(f"--model expects NAME=DIR, got {spec!r}")
        methods[name] = OnnxSSN(folder)
        if methods[name].resolution != n:
            raise SystemExit(f"{folder} renders {methods[name].resolution}-pixel frames; the data has N = {n}")
    rows = [Row(name, m) for name, m in methods.items()]
    for name in args.with_camera:
        rows.append(Row(f"{name} + camera", methods[name], camera=True))
    for name in args.with_gt_ao:
        rows.append(Row(f"{name} + GT AO", methods[name], gt_ao=True))
    return rows


def family_lights(seed: int, view: int, family: str, count: int, rows_hb: int) -> tuple[np.ndarray, np.ndarray]:
    """The light maps of one view and family on the basis grid and on the network's 16 x 32 grid."""
    lights = sample_family(np.random.default_rng([seed, FAMILIES.index(family), view]), count, family)
    return render_lights(lights, rows_hb), render_lights(lights, 16)


def evaluate_families(args: argparse.Namespace, store=None) -> dict:
    families = [f for f in args.families.split(",") if f]
    unknown = set(families) - set(FAMILIES)
    if unknown:
        raise SystemExit(f"--families: unknown {sorted(unknown)}; choose from {', '.join(FAMILIES)}")
    store = store if store is not None else ViewStore(args.data)
    n, rows_hb = store.meta["res"], store.meta["elm_rows"]
    rows = build_rows(args, n)
    labels = [r.label for r in rows]
    ids = sorted(i for k in KINDS for i in store.view_ids(args.split, k))
    if args.max_views and len(ids) > args.max_views:
        ids = [ids[int(j)] for j in np.linspace(0, len(ids) - 1, args.max_views).round()]
    records: list[dict] = []  # one per image: family, kind, pitch, metrics per row, sun geometry per row
    t0 = time.perf_counter()
    prog = Progress(len(ids), every=max(1, len(ids) // 20))
    for j, i in enumerate(ids):
        v = store.load(i)
        info = store.info(i)
        cam = np.array(camera_input(info, n))
        aos = {r.label: r.ao(v.mask, v.ao, cam) for r in rows}  # once per view, not per family
        for family in families:
            elm_hb, elm16 = family_lights(args.seed, j, family, args.per_view, rows_hb)
            gt = np.stack([store.shadow(v.occlusion, e) for e in elm_hb])
            preds = {r.label: r.predict(v.mask, aos[r.label], elm16, cam) for r in rows}
            for b in range(len(gt)):
                rec = {
                    "family": family,
                    "kind": info["kind"],
                    "pitch": float(info["pitch"]),
                    "metrics": {lab: all_metrics(preds[lab][b], gt[b]) for lab in labels},
                }
                if family == "sun":
                    rec["sun"] = {lab: sun_geometry(preds[lab][b], gt[b], v.mask) for lab in labels}
                records.append(rec)
        prog.update(j + 1, info["mesh_id"])
    prog.close()
    results = summarise(records, labels, families)
    results.update(
        {
            "split": args.split,
            "views": len(ids),
            "per_view": args.per_view,
            "N": n,
            "data": str(args.data),
            "seconds": time.perf_counter() - t0,
            "seed": args.seed,
        }
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "families.json").write_text(json.dumps(results, indent=1))
    (out / "families.md").write_text(families_markdown(results))
    sun_grid(store, ids, rows, out / "sun_grid.png", rows_hb)
    return results


def summarise(records: list[dict], labels: list[str], families: list[str]) -> dict:
    """Mean metrics per family (all kinds, per kind, per pitch) and the sun family's geometry medians."""
    out: dict = {"rows": labels, "families": {}}
    for family in families:
        recs = [r for r in records if r["family"] == family]
        fam: dict = {"images": len(recs), "all": _means(recs, labels), "kinds": {}, "pitches": {}}
        for kind in KINDS:
            part = [r for r in recs if r["kind"] == kind]
            if part:
                fam["kinds"][kind] = {"images": len(part), **_means(part, labels)}
        for group, rows in pitch_groups([r["pitch"] for r in recs]).items():
            part = [recs[i] for i in rows]
            fam["pitches"][group] = {"images": len(part), **_means(part, labels)}
        if family == "sun":
            fam["geometry"] = {}
            for lab in labels:
                geo = [r["sun"][lab] for r in recs if r["sun"][lab] is not None]
                errors = np.array([g["direction_error"] for g in geo])
                ratios = np.array([g["length_ratio"] for g in geo])
                fam["geometry"][lab] = {
                    "images": len(geo),
                    "median_direction_error": float(np.median(errors)) if geo else float("nan"),
                    "median_length_ratio": float(np.median(ratios)) if geo else float("nan"),
                    "ratio_within_0.8_1.25": float(np.mean((ratios >= 0.8) & (ratios <= 1.25))) if geo else 0.0,
                }
        out["families"][family] = fam
    return out


def _means(recs: list[dict], labels: list[str]) -> dict:
    return {"metrics": {lab: mean_metrics([r["metrics"][lab] for r in recs]) for lab in labels}}


def families_markdown(results: dict) -> str:
    """Tables per family: the four metrics over all kinds, ZNCC / DSSIM per kind and per pitch, sun geometry."""
    labels = results["rows"]
    lines = []
    for family, fam in results["families"].items():
        lines += [
            f"### {family} ({fam['images']} images)\n",
            "| row | " + " | ".join(NAMES) + " |",
            "|---" * (1 + len(NAMES)) + "|",
        ]
        for lab in labels:
            m = fam["all"]["metrics"][lab]
            lines.append(f"| {lab} | " + " | ".join(f"{m[k]:.4f}" for k in NAMES) + " |")
        groups = [(k, fam["kinds"][k]) for k in fam["kinds"]] + [
            (f"pitch {p}", fam["pitches"][p]) for p in fam["pitches"]
        ]
        lines += [
            "",
            "| ZNCC / DSSIM | " + " | ".join(f"{g} ({part['images']})" for g, part in groups) + " |",
            "|---" * (1 + len(groups)) + "|",
        ]
        for lab in labels:
            cells = [f"{part['metrics'][lab]['ZNCC']:.3f} / {part['metrics'][lab]['DSSIM']:.3f}" for _, part in groups]
            lines.append(f"| {lab} | " + " | ".join(cells) + " |")
        if "geometry" in fam:
            lines += [
                "",
                "| sun geometry | images | median direction error (deg) | median length ratio | ratio in [0.8, 1.25] |",
                "|---|---:|---:|---:|---:|",
            ]
            for lab in labels:
                g = fam["geometry"][lab]
                lines.append(
                    f"| {lab} | {g['images']} | {g['median_direction_error']:.1f} | "
                    f"{g['median_length_ratio']:.2f} | {g['ratio_within_0.8_1.25']:.0%} |"
                )
        lines.append("")
    return "\n".join(lines)


def sun_grid(store, ids: list[int], rows: list[Row], path: Path, rows_hb: int, views: int = 3) -> None:
    """A picture grid: a few views under one sun at several elevations; ground truth, then every row."""
    pictures = []
    for i in [ids[int(j)] for j in np.linspace(0, len(ids) - 1, views).round()] if ids else []:
        v = store.load(i)
        cam = np.array(camera_input(store.info(i), store.meta["res"]))
        aos = [r.ao(v.mask, v.ao, cam) for r in rows]
        for elevation in SUN_ELEVATIONS:
            light = LightMap([GaussianLight(SUN_AZIMUTH_U, 1.0 - elevation / 90.0, 0.002, 1.0)])
            gt = store.shadow(v.occlusion, render_light_map(light, rows_hb))
            elm16 = render_light_map(light, 16)[None]
            shadows = [gt] + [r.predict(v.mask, ao, elm16, cam)[0] for r, ao in zip(rows, aos, strict=True)]
            pictures.append([on_ground(s, v.mask) for s in shadows])
    if pictures:
        labels = [f"truth (sun at {', '.join(f'{e:g}' for e in SUN_ELEVATIONS)} deg)"] + [r.label for r in rows]
        image_grid(pictures, path, labels, cell=160)


def on_ground(s: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """A shadow as it looks: dark on a white ground, the object in mid grey over it."""
    return np.where(mask > 0.5, 0.55, 1.0 - s)
