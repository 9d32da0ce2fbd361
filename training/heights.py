"""Make the camera estimator's data: ``python -m training.heights make``.

    python -m training.heights make --split train --cameras continuous paper --out data/heights128/train.npz

Needs only the meshes (no shadow bases); what a view holds and how it is drawn: :mod:`training.data.camera_views`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .data.camera_views import make
from .data.views import add_split_arguments


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.heights", description=(__doc__ or "").split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make", help="masks and camera inputs of a split's views, and the camera estimator's inputs")
    add_split_arguments(m)
    m.add_argument(
        "--view-seed", type=int, help="draw other views of the same items (default: --seed, the dataset's views)"
    )
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    make(args.split, args.cameras, Path(args.out), args.seed, view_seed=args.view_seed)


if __name__ == "__main__":
    main()
