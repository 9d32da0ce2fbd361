"""A training checkpoint rebuilt from an exported ONNX graph, so that a shipped model can be fine-tuned where its
training runs are gone: ``python -m training.onnx_weights ssn_engine/models/sr.onnx --out runs/sr_v34/base.pt``
(then ``--init-from`` it; not a run folder's ``last.pt``, which ``training.train`` would try to resume).

The exporter (:mod:`training.export`) keeps the convolutions' names (``net.<parameter>``) and folds each
GroupNorm's weight and bias into two anonymous constants, in the order the forward pass uses them; the network's
own GroupNorms, in module order, take them back. A mirror-averaged graph (``export --mirror-average``, names
``net.net.<parameter>``) gives back the network inside the average; a graph of the mean of several networks (the
shipped AOP, ``nets.<k>.``) gives back the one of ``--member k``. The rebuilt network is checked against the
graph on random inputs (``--tol``).

``--reexport GRAPH`` writes the whole function (every member, the mirror average) again in the exporter's current
form instead: ``python -m training.onnx_weights ssn_engine/models/sr.onnx --reexport runs/sr.onnx`` gave the
shipped graphs of earlier exporters GroupNorms with fixed shapes (docs/engine.md, "Speed").
"""

from __future__ import annotations

import argparse
from pathlib import Path

from . import checkpoint
from .graph_weights import rebuild, reexport
from .onnx_graphs import TOL


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.onnx_weights", description=(__doc__ or "").split("\n")[0])
    p.add_argument("graph", type=Path, help="aop.onnx or sr.onnx")
    to = p.add_mutually_exclusive_group(required=True)
    to.add_argument("--out", type=Path, help="checkpoint to write")
    to.add_argument("--reexport", type=Path, help="graph to write: the same function in the current export form")
    p.add_argument("--groups", type=int, default=8, help="GroupNorm groups of the trained network")
    p.add_argument("--tol", type=float, default=TOL, help="largest difference allowed from the graph")
    p.add_argument("--member", type=int, help="of a graph that is the mean of several networks (the AOP): which one")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        if args.reexport:
            diff = reexport(args.graph, args.reexport, args.groups, args.tol)
            print(f"{args.reexport}: {diff:.1e} off {args.graph}")
            return 0
        _, ck = rebuild(args.graph, args.groups, args.tol, args.member)
    except ValueError as exc:
        raise SystemExit(f"{args.graph}: {exc}") from None
    checkpoint.save(args.out, ck)
    print(f"{args.out}: {ck['module']} {ck['unet']}, {ck['parity']:.1e} off {args.graph}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
