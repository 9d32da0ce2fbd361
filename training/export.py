"""Export AOP and SR to the engine's ONNX contract, check parity with torch, time SR, and optionally install.

``python -m training.export --aop runs/aop/last.pt --sr runs/sr/last.pt --out runs/export``
writes aop.onnx, sr.onnx and model.json (:class:`ssn_engine.model_config.ModelConfig`, the contract of
ssn_engine/methods/onnx_ssn.py):
- aop.onnx: "mask" [batch, 1, R, R] -> "ao" [batch, 1, R, R], clamped to [0, 1]
- aop_camera.onnx (--aop-camera): an AOP trained with the camera input (train --camera), which also takes
  "camera" [batch, 2], horizon row and focal length in frames (pixels / N)
- sr.onnx: "mask", "ao" [batch, 1, R, R], "elm" [batch, 16, 32] (network_elm-normalised) -> "shadow" [batch, 1, R, R];
  a geometry-guided SR (train --card) also takes "card" [batch, 1, R, R], the geometric card's shadow
``--aop`` may name an installed aop.onnx instead of checkpoints: that graph is reused as it is (its record is read
from the model.json beside it), so a new SR can ship with the AOP of an earlier release.
Weights are stored as float32; each graph must stay within ``--tol`` of its torch network.
``--install DIR`` copies the model and a model card there (the engine's default is ssn_engine/models).
The work is :func:`training.model_export.export_model`'s.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .model_export import ExportError, ExportOptions, export_model, reuses_aop_graph
from .onnx_graphs import TOL


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.export", description=(__doc__ or "").split("\n")[0])
    p.add_argument(
        "--aop",
        nargs="+",
        required=True,
        help="AOP checkpoint(s); several: one graph of their mean; or an installed aop.onnx, reused as it is",
    )
    p.add_argument(
        "--aop-camera",
        nargs="+",
        help="camera-taking AOP checkpoint(s) (train --camera; several: their mean): aop_camera.onnx, the AOP "
        "the engine runs for calls that give the camera input",
    )
    p.add_argument("--sr", required=True)
    p.add_argument("--out", default="runs/export")
    p.add_argument("--data", default="data/ssn128", help="dataset for test inputs and the card's attribution")
    p.add_argument("--tol", type=float, default=TOL, help="the largest difference a graph may have to its network")
    p.add_argument(
        "--floor",
        type=float,
        default=0.0,
        help="model.json output_floor: the engine removes shadow values below it (evaluate --floor)",
    )
    p.add_argument(
        "--floor-small-lights",
        type=float,
        default=None,
        help="model.json output_floor_small_lights: the floor for one or two small lights (default: --floor)",
    )
    p.add_argument(
        "--shadow-reach",
        type=float,
        default=0.0,
        help="model.json shadow_reach: keep the shadow within this many pixels (N = 256) of the card's shadow "
        "and the cutout (a geometry-guided SR only; 0: off)",
    )
    p.add_argument(
        "--ao-gamma",
        type=float,
        default=1.0,
        help="model.json ao_gamma: the engine raises the predicted AO map to this power (1: as predicted)",
    )
    p.add_argument(
        "--card-blur",
        type=float,
        help="model.json card_blur: blur the card's shadow by a Gaussian of this many pixels (R) before the SR "
        "(a geometry-guided SR only; 0: off; default: the SR's training option, train --card-blur)",
    )
    p.add_argument(
        "--mirror-average",
        action="store_true",
        help="export each network as training.model.MirrorAverage (twice the compute, mirror-symmetric)",
    )
    p.add_argument(
        "--aop-without-mirror",
        action="store_true",
        help="with an installed, mirror-averaged aop.onnx as --aop: reuse it without its mirror average "
        "(each network once; half the AOP's compute)",
    )
    p.add_argument("--install", help="copy the model here (e.g. ssn_engine/models)")
    p.add_argument(
        "--command",
        default="training/reproduce.sh",
        help="the reproducing command recorded in the card",
    )
    p.add_argument("--trained-on", default="", help="the machine the SR was trained on, for the card")
    args = p.parse_args(argv)
    try:
        reuses_aop_graph(args.aop, args.aop_without_mirror)
    except ExportError as exc:
        p.error(str(exc))
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    options = ExportOptions(**{**vars(args), "out": Path(args.out), "install": args.install and Path(args.install)})
    try:
        export_model(options)
    except ExportError as exc:
        print(exc, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
