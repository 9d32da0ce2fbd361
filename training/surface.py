"""The surface model: a pixel height for each pixel of a cutout.

``python -m training.surface make|train|average|install``:

    python -m training.surface make --split train --cameras continuous paper --out data/surface128/train.npz
    python -m training.surface make --split val --cameras continuous paper --out data/surface128/val.npz
    python -m training.surface train --data data/surface128 --run runs/surface --minutes 7
    python -m training.surface average ssn_engine/models/surface.onnx runs/surface/last.pt --share 0.5 \
        --data data/surface128 --out runs/surface/average.pt
    python -m training.surface install runs/surface/last.pt --models ssn_engine/models

What a view holds: :mod:`training.data.surface_views`; the network and its loss: :mod:`training.surface_model`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .data.surface_views import make
from .data.sources import DEFAULT_SOURCES, SOURCES
from .data.views import add_split_arguments
from .surface_model import WIDTHS, average, install, train


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.surface", description=(__doc__ or "").split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make", help="masks, camera inputs and pixel heights of a split's views")
    add_split_arguments(m)
    m.add_argument(
        "--sources",
        nargs="+",
        choices=SOURCES,
        default=list(DEFAULT_SOURCES),
        help="the kinds of items viewed (default: %(default)s)",
    )
    m.add_argument(
        "--stretch",
        type=float,
        default=0.0,
        help="stretch each view's shape along x, y and z by up to 1 + STRETCH (or shrink by as much): other shapes",
    )
    m.add_argument(
        "--quadrupeds", type=int, default=0, help="how many procedural animals the quadruped source draws (all splits)"
    )
    m.add_argument("--grounded", type=int, default=0, help="how many objects the grounded source draws (all splits)")
    t = sub.add_parser("train", help="train the surface model on a folder's train.npz, scored on its val.npz")
    t.add_argument("--data", required=True)
    t.add_argument("--sets", nargs="+", help="the training files' names in --data (default: every train*.npz)")
    t.add_argument("--run", required=True, help="folder for checkpoints and the log")
    t.add_argument("--minutes", type=float, default=7.0, help="stop after this long (the schedule fits it)")
    t.add_argument("--batch", type=int, default=64)
    t.add_argument("--lr", type=float, default=2e-3)
    t.add_argument("--device", default="cuda", help="torch device (cuda, cpu)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--widths", type=int, nargs="+", help="the U-Net's width per stage (default: the shipped one's)")
    t.add_argument(
        "--init", help="a checkpoint or an installed surface.onnx to go on from (fine-tuning it; its widths)"
    )
    t.add_argument("--resume", action="store_true", help="go on with the run in --run where it stopped")
    t.add_argument(
        "--depth",
        action="store_true",
        help="read the object's depth at each pixel too (a second output; one added to an --init network's)",
    )
    t.add_argument(
        "--depth-weight",
        type=float,
        default=0.0,
        help="rows of R: the depth's L1 weighted by 1 + the true depth / this (0: a plain mean)",
    )
    a = sub.add_parser("average", help="a checkpoint whose weights lie between two networks' (scored on val.npz)")
    a.add_argument("first", help="a checkpoint or an installed surface.onnx (the network started from)")
    a.add_argument("second", help="a checkpoint or an installed surface.onnx of the same shape (the one trained on)")
    a.add_argument("--share", type=float, required=True, help="how much of the second's weights (0 to 1)")
    a.add_argument("--data", required=True, help="the folder whose val.npz scores the average")
    a.add_argument("--out", required=True, help="the checkpoint written")
    e = sub.add_parser("install", help="a checkpoint's graph into a model folder (model.json and the card too)")
    e.add_argument("checkpoint")
    e.add_argument("--models", required=True, help="the model folder (ssn_engine/models)")
    e.add_argument(
        "--second",
        help="an installed surface.onnx kept beside it (the one replaced, say): each pixel's height the higher of "
        "the two readings",
    )
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    if args.command == "make":
        make(
            args.split,
            args.cameras,
            Path(args.out),
            args.seed,
            tuple(args.sources),
            stretch=args.stretch,
            quadrupeds=args.quadrupeds,
            grounded=args.grounded,
        )
    elif args.command == "train":
        widths = tuple(args.widths) if args.widths else WIDTHS
        init = Path(args.init) if args.init else None
        data = Path(args.data)
        sets = [data / f"{name}.npz" for name in args.sets] if args.sets else sorted(data.glob("train*.npz"))
        train(
            data,
            sets,
            Path(args.run),
            args.minutes,
            args.batch,
            args.lr,
            args.device,
            args.seed,
            widths,
            init,
            args.resume,
            args.depth,
            args.depth_weight,
        )
    elif args.command == "average":
        row = average(Path(args.first), Path(args.second), args.share, Path(args.data), Path(args.out))
        print(f"wrote {args.out}: " + ", ".join(f"{k} {v:.3f}" for k, v in row.items()))
    else:
        second = Path(args.second) if args.second else None
        diff = install(Path(args.checkpoint), Path(args.models), second)
        print(f"installed {args.checkpoint} into {args.models} (graph within {diff:.1e} of torch)")


if __name__ == "__main__":
    main()
