"""Train the AOP or the SR module (paper Section 5): ``python -m training.train --module aop|sr --run runs/NAME``.

Resumable: the run directory holds ``last.pt`` (written every ``--ckpt-minutes``
and on SIGTERM/SIGINT), ``best.pt`` (lowest validation loss), ``log.csv``,
``loss.png`` and ``samples_*.png``; running the same command again resumes.
On several GPUs or machines, launch with torchrun (DistributedDataParallel):
``torchrun --nproc_per_node=4 -m training.train --module sr ...``.

Schedule: Adam, learning rate ``--lr`` (1e-3), linear warm-up over
``--warmup`` steps, then cosine decay to ``--lr-min`` at ``--steps``.
"""

from __future__ import annotations

import argparse
import sys

from ssn_engine.model_config import MAX_CARD_BLUR

from .data.packed import is_packed
from .elm import TRAIN_MIX
from .trainer import run


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.train", description=(__doc__ or "").split("\n")[0])
    p.add_argument("--module", choices=["aop", "sr"], required=True)
    p.add_argument(
        "--target",
        choices=["shadow", "irradiance"],
        default="shadow",
        help="SR target: the conventions' shadow s (SSN) or raw irradiance E (Non-inv-SSN ablation)",
    )
    p.add_argument(
        "--data",
        nargs="+",
        default=["data/ssn128"],
        help="dataset roots (training.data.store.ViewStore), read as one (e.g. one shape set at two camera sets)",
    )
    p.add_argument("--run", required=True, help="run directory (checkpoints, logs)")
    p.add_argument("--resolution", type=int, default=128)
    p.add_argument("--widths", default="8,16,32,64,96,128", help="channels per U-Net stage")
    p.add_argument("--groups", type=int, default=8)
    p.add_argument("--batch", type=int, default=16, help="batch per process")
    p.add_argument("--steps", type=int, default=6000)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--lr-min", type=float, default=1e-5)
    p.add_argument("--warmup", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    p.add_argument("--cache-views", type=int, default=300, help="views kept in memory (rotating)")
    p.add_argument("--elms-per-view", type=int, default=4, help="SR: ELMs per view in a batch (AOP: 1)")
    p.add_argument("--swap-every", type=int, default=1, help="replace a cached view every this many batches")
    p.add_argument(
        "--balance-kinds",
        action="store_true",
        help="draw objects, humans and animals equally often (default: in proportion to their views)",
    )
    p.add_argument(
        "--flip",
        action="store_true",
        help="mirror half of the samples left to right (frames in x, light maps in azimuth)",
    )
    p.add_argument(
        "--ao-from",
        nargs="+",
        help="SR: AOP checkpoint(s) whose predicted AO (several: their mean, as "
        "export --aop), or an exported aop.onnx graph (such as the shipped ssn_engine/models/aop.onnx), "
        "replaces the (perturbed) ground-truth AO in a fraction --ao-from-prob of the samples "
        "(the AO SR gets in use)",
    )
    p.add_argument(
        "--card",
        action="store_true",
        help="SR: geometry-guided; the geometric card's shadow for the "
        "same light map is an input and the base of the output (training.model.SRNet)",
    )
    p.add_argument(
        "--camera",
        action="store_true",
        help="AOP: also takes the camera input (horizon row, focal length) as ground-geometry channels "
        "(training.model.AOPNet); export --aop-camera ships it as the AOP of calls that give the camera input",
    )
    p.add_argument(
        "--true-camera",
        type=float,
        default=0.5,
        help="SR --card, AOP --camera: share of samples whose card is traced with (AOP: who get) the view's true "
        "camera input (the others: the blind camera, --blind-camera-error)",
    )
    p.add_argument(
        "--blind-camera-error",
        type=float,
        nargs=2,
        metavar=("HORIZON", "LOG_FOCAL"),
        help="SR --card, AOP --camera: the blind camera is the view's true camera moved by Laplace noise of these "
        "scales (horizon row in frames, log focal length), as the shipped camera estimator misses it on the "
        "validation split (docs/training.md); default: the conventions' default camera (AOP: the true camera)",
    )
    p.add_argument(
        "--card-blur",
        type=float,
        default=0.0,
        help="SR --card: blur the card's shadow by a Gaussian of this many pixels (R), as the engine does for a model "
        "whose model.json sets card_blur (training.export takes it from the checkpoint)",
    )
    p.add_argument(
        "--lights",
        choices=["table1", "mix"],
        default="table1",
        help=f"SR: light maps from the paper's Table 1, or the mixture of light families {TRAIN_MIX} (training.elm)",
    )
    p.add_argument(
        "--ao-from-camera",
        nargs="+",
        help="SR with --ao-from and --card: a camera-taking AOP (checkpoints, or an exported aop_camera.onnx) "
        "whose AO, predicted with the view's true camera, replaces --ao-from's in the samples whose card is "
        "traced with the true camera, as the engine feeds a call given the camera input",
    )
    p.add_argument("--ao-from-prob", type=float, default=0.5)
    p.add_argument(
        "--zncc-weight",
        type=float,
        default=0.0,
        help="SR: add this x (1 - ZNCC), each image on its own, to the per-pixel L2",
    )
    p.add_argument("--ckpt-minutes", type=float, default=4.0)
    p.add_argument("--refresh-minutes", type=float, default=10.0, help="re-open the store (growing dataset)")
    p.add_argument("--val-every", type=int, default=250)
    p.add_argument("--val-samples", type=int, default=48)
    p.add_argument("--log-every", type=int, default=20)
    p.add_argument(
        "--max-minutes", type=float, default=0.0, help="stop (with a checkpoint) after this long; 0: no limit"
    )
    p.add_argument("--fresh", action="store_true", help="ignore an existing checkpoint in --run")
    p.add_argument(
        "--init-from",
        help="fine-tune: start a new run from this checkpoint's weights (same module, "
        "target and U-Net; an AOP without --camera may start a --camera one) with a fresh optimizer and schedule",
    )
    args = p.parse_args(argv)
    if is_packed(args.data) and args.module != "aop":
        p.error(f"--data {args.data[0]} is a packed file (masks and AO maps, no shadow bases): it trains an AOP")
    if (args.card or args.lights != "table1") and args.module != "sr":
        p.error("--card and --lights apply to SR (--module sr)")
    if args.camera and args.module != "aop":
        p.error("--camera applies to AOP (--module aop); a geometry-guided SR takes the camera through its card")
    if args.card_blur and not args.card:
        p.error("--card-blur blurs the card: give --card")
    if args.ao_from_camera and not (args.ao_from and args.card):
        p.error(
            "--ao-from-camera replaces --ao-from's maps where the card uses the true camera: give --ao-from and --card"
        )
    if not 0.0 <= args.card_blur <= MAX_CARD_BLUR:
        p.error(f"--card-blur must be in [0, {MAX_CARD_BLUR}] pixels")
    args.widths = tuple(int(w) for w in str(args.widths).split(","))
    return args


def run_args(argv: list[str] | None) -> argparse.Namespace:
    """The command line; an AOP's target is the AO map."""
    args = parse_args(argv)
    if args.module == "aop":
        args.target = "ao"
    return args


def main(argv: list[str] | None = None, store=None) -> int:
    """Train; ``store`` replaces ``ViewStore(--data)`` (tests pass an in-memory stand-in)."""
    run(run_args(argv), store)
    return 0


if __name__ == "__main__":
    sys.exit(main())
