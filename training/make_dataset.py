"""Meshes -> SSN training set (the paper's Section 4), resumable and shardable.

    python -m training.make_dataset --out data/ssn256 --res 256 --workers 2 --seed 0
    python -m training.make_dataset --out data/ssn256 --res 256 --shard 0/2   # one of two machines

Each finished mesh is a checkpoint: rerunning the same command skips it.
See training/data/README.md for the layout and docs/dataset.md for figures.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import sys
import time
import traceback
from pathlib import Path

from training.data import writer
from training.data.card import write_card
from training.data.contact_sheet import write_contact_sheet
from training.data.generate import render_item
from training.data.render_bases import set_threads
from training.data.sources import DEFAULT_SOURCES, SOURCES, all_items
from training.data.store import DATASET_JSON
from training.data.views import CAMERA_TEXT, CAMERAS, FOV_RANGE, PITCH_RANGE, PITCHES, VIEWS, YAW_RANGE, YAWS
from training.progress import Progress

FORMAT_VERSION = 1


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.make_dataset", description=(__doc__ or "").split("\n")[0])
    p.add_argument("--out", required=True, type=Path, help="dataset directory")
    p.add_argument("--res", type=int, default=256, help="frame size N")
    p.add_argument("--workers", type=int, default=2, help="processes (one mesh at a time each)")
    p.add_argument("--seed", type=int, default=0, help="seed of fields of view, jitter and generated shapes")
    p.add_argument("--shard", default="0/1", help="i/k: this process renders items i, i+k, i+2k, ...")
    p.add_argument("--elm-rows", type=int, default=16, help="basis grid rows Hb (grid Hb x 2Hb)")
    p.add_argument("--samples", type=int, default=16, help="directions per texel (a square number)")
    p.add_argument("--sources", default=",".join(DEFAULT_SOURCES), help=f"comma list of {','.join(SOURCES)}")
    p.add_argument("--procedural", type=int, default=160, help="number of procedural shapes")
    p.add_argument("--humans", type=int, default=120, help="number of anny humans")
    p.add_argument("--quadrupeds", type=int, default=0, help="number of procedural animals")
    p.add_argument("--grounded", type=int, default=0, help="number of objects with flat parts on the ground")
    p.add_argument("--limit", type=int, default=0, help="only the first LIMIT items of the ordered list")
    p.add_argument("--only", default="", help="comma list of item ids to render")
    p.add_argument("--threads", type=int, default=0, help="numba threads per worker (0: cores / workers)")
    p.add_argument(
        "--cameras",
        choices=CAMERAS,
        default="paper",
        help=f"the 15 views of each shape: paper ({CAMERA_TEXT['paper']}) or continuous ({CAMERA_TEXT['continuous']})",
    )
    p.add_argument("--no-card", action="store_true", help="skip the dataset card and contact sheet")
    return p.parse_args(argv)


def _init_worker(threads: int) -> None:
    set_threads(threads)


def _run_item(job: tuple) -> dict:
    item, root, res, elm_rows, samples, seed, cameras = job
    try:
        return render_item(item, root, res, elm_rows, samples, seed, cameras)
    except Exception:  # one broken shape must not stop the run; it is reported and retried next run
        return {"id": item.id, "error": traceback.format_exc()}


def _dataset_meta(args: argparse.Namespace) -> dict:
    return {
        "format": "ssn-shadow-bases",
        "version": FORMAT_VERSION,
        "res": args.res,
        "elm_rows": args.elm_rows,
        "samples_per_texel": args.samples,
        "seed": args.seed,
        "views_per_mesh": VIEWS,
        "cameras": args.cameras,
        "yaws": list(YAWS) if args.cameras == "paper" else f"uniform in {list(YAW_RANGE)}",
        "pitches": list(PITCHES) if args.cameras == "paper" else f"uniform in {list(PITCH_RANGE)}",
        "fov_range": list(FOV_RANGE),
    }


def _check_meta(root: Path, meta: dict) -> None:
    path = root / DATASET_JSON
    if path.exists():
        old = json.loads(path.read_text())
        old.setdefault("cameras", "paper")  # sets made before the setting existed
        for key in ("res", "elm_rows", "samples_per_texel", "seed", "version", "cameras"):
            if old.get(key) != meta[key]:
                sys.exit(f"{path}: {key} is {old.get(key)!r}, this run asks for {meta[key]!r}; use another --out")
    else:
        root.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}")
        tmp.write_text(json.dumps(meta, indent=1))
        os.replace(tmp, path)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    root: Path = args.out
    meta = _dataset_meta(args)
    _check_meta(root, meta)
    shard, shards = (int(x) for x in args.shard.split("/"))
    sources = tuple(s for s in args.sources.split(",") if s)
    items = all_items(sources, args.procedural, args.humans, args.seed, args.quadrupeds, args.grounded)
    if args.only:
        wanted = set(args.only.split(","))
        items = [it for it in items if it.id in wanted]
    if args.limit:
        items = items[: args.limit]
    items = items[shard::shards]
    writer.remove_stale(root) if shards == 1 else None
    todo = [it for it in items if not writer.is_done(root, it.id)]
    print(
        f"{len(items)} items in shard {args.shard}, {len(items) - len(todo)} already done, "
        f"{len(todo)} to render at N={args.res}, grid {args.elm_rows}x{2 * args.elm_rows}, "
        f"{args.samples} directions per texel, {args.workers} workers",
        file=sys.stderr,
        flush=True,
    )
    jobs = [(it, root, args.res, args.elm_rows, args.samples, args.seed, args.cameras) for it in todo]
    threads = args.threads or max(1, (os.cpu_count() or 1) // max(args.workers, 1))
    start = time.time()
    progress, done, views = Progress(len(jobs), every=1), 0, 0
    failures = []
    if args.workers <= 1:
        _init_worker(threads)
        results = map(_run_item, jobs)
        pool = None
    else:
        pool = mp.get_context("spawn").Pool(args.workers, _init_worker, (threads,))
        results = pool.imap_unordered(_run_item, jobs)
    for r in results:
        if "error" in r:
            failures.append(r)
            print(f"FAILED {r['id']}:\n{r['error']}", file=sys.stderr, flush=True)
        done, views = done + 1, views + r.get("views", 0)
        progress.update(done, f"meshes, {views} views, {r['id']}")
    progress.close()
    if pool is not None:
        pool.close()
        pool.join()
    with open(root / "runs.jsonl", "a") as fh:
        fh.write(
            json.dumps(
                {
                    "shard": args.shard,
                    "items": len(items),
                    "rendered": len(jobs) - len(failures),
                    "failed": [f["id"] for f in failures],
                    "wall_seconds": time.time() - start,
                    "workers": args.workers,
                    "threads": threads,
                    "argv": sys.argv[1:],
                }
            )
            + "\n"
        )
    if not args.no_card:
        write_card(root)
        write_contact_sheet(root)
    return 0


if __name__ == "__main__":
    sys.exit(main())
