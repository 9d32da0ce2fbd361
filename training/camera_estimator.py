"""Train the camera estimator: a small CNN that reads a view's horizon row and focal length from its mask.

``python -m training.camera_estimator --data data/heights128 --out runs/camera`` reads the masks and true camera
inputs that ``training.heights make`` wrote (both camera sets: the paper's five views and continuous ones), puts
each mask in the engine's canonical framing (:mod:`ssn_engine.methods.camera_estimate`), trains on the train
split (mirrored and slightly rescaled masks too: the camera does not change), keeps the step with the lowest
validation error, reports it by pitch and exports ``camera.onnx`` ("mask" [b, 1, 64, 64] -> "camera" [b, 2]).

The horizon is read as a distribution over bins (cross-entropy on soft labels) and the graph returns its median:
where the silhouette leaves the pitch ambiguous a regression is pulled to the middle camera by an amount that
varies from run to run, while the median of a classifier's distribution stays with the likelier camera. The
graph also averages the mask with its mirror image. With ``--install ssn_engine/models`` the run is then
installed into the model folder (``--minutes 0``: install the run in ``--out`` without training).

``--data`` may name several folders, ``training.surface make`` ones too: their sets hold many more shapes than the
dataset's (procedural animals, people in poses, objects with parts on the ground), on which the shipped estimator
was fine-tuned (``--init-from``, docs/training.md, "Stage 5").

On a GPU machine, where the views do not travel: ``--write-examples FILE`` here packs both splits' inputs (about
10 MB for 32,160 views), and ``--examples FILE --device cuda`` there trains on them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .camera_net import install, train, write_examples


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m training.camera_estimator",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--data",
        nargs="+",
        type=Path,
        default=[Path("data/heights128")],
        help="`training.heights make` folders, or `training.surface make` ones (their many shapes: procedural "
        "animals, people in poses, objects with parts on the ground)",
    )
    parser.add_argument("--out", default="runs/camera")
    parser.add_argument("--minutes", type=float, default=30.0, help="training time; 0: only --install")
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--lr", type=float, default=1e-3)
    parser.add_argument("--width", type=int, default=32)
    parser.add_argument("--val-every", type=int, default=250)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--kind-weights",
        type=float,
        nargs=3,
        default=(1.0, 1.0, 1.0),
        metavar=("OBJECT", "HUMAN", "ANIMAL"),
        help="draw views of each kind this many times as often as their share",
    )
    parser.add_argument("--device", default="cpu", help="torch device to train on (cuda: a GPU)")
    parser.add_argument("--examples", help="read both splits from this --write-examples file instead of --data")
    parser.add_argument("--write-examples", help="only write --data's examples to this file (for a GPU machine)")
    parser.add_argument(
        "--sharp-input",
        action="store_true",
        help="train on the inputs `heights make` writes from the masks at N = 256 (as the engine makes them) "
        "instead of the 128-pixel masks scaled up (the shipped estimator's)",
    )
    parser.add_argument("--init-from", help="start from the weights of an exported camera.onnx (a fine-tune)")
    parser.add_argument("--install", help="then install the estimator into this model folder (ssn_engine/models)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    if args.write_examples:
        write_examples(args.data, Path(args.write_examples), args.sharp_input)
        return
    if args.minutes > 0:
        train(args)
    if args.install:
        install(Path(args.out), Path(args.install))


if __name__ == "__main__":
    main()
