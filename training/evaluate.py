"""Paper Section 6 benchmark: ``python -m training.evaluate --aop A.pt --sr S.pt [--noninv N.pt]``.

On the test split, objects (object + animal) and humans separately, every view
is paired with ``--per-view`` ELMs from a fixed pool of ``--n-elms`` random
Table 1 light maps (seeded). Rows: the engine's geometric card baseline,
Non-inv-SSN (SR trained on raw irradiance, converted to s = 1 - E / E0), SSN
(AOP -> SR), GT-AO-SSN (ground-truth AO into SR). Metrics on s at the
dataset's resolution N; networks at R see frames resampled N -> R -> N as in
the engine.

``--families``: the evaluation by light family of installed model folders
(:mod:`training.evaluate_families`).
"""

from __future__ import annotations

import argparse
import sys

from .elm import FAMILIES
from .evaluate_families import evaluate_families, families_markdown
from .evaluation import evaluate, tables_markdown


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.evaluate", description=(__doc__ or "").split("\n")[0])
    p.add_argument("--data", default="data/ssn128")
    p.add_argument("--split", default="test")
    p.add_argument(
        "--aop",
        nargs="+",
        help="AOP checkpoint(s), several: the mean of their AO maps (without --aop "
        "and --sr: the geometric baseline alone)",
    )
    p.add_argument("--sr", help="SR checkpoint (shadow target)")
    p.add_argument("--noninv", help="SR checkpoint trained on irradiance (Non-inv-SSN)")
    p.add_argument("--no-geometric", action="store_true")
    p.add_argument("--geo-cache", help="npz of geometric predictions to reuse and extend (they do not change)")
    p.add_argument("--n-elms", type=int, default=64, help="size of the fixed pool of random ELMs")
    p.add_argument("--per-view", type=int, default=2, help="ELMs per view")
    p.add_argument("--max-views", type=int, default=0, help="at most this many views per group (evenly spaced); 0: all")
    p.add_argument(
        "--floor",
        type=float,
        default=0.0,
        help="output floor applied to the networks' shadows (the shipped model.json's output_floor)",
    )
    p.add_argument(
        "--mirror-average",
        action="store_true",
        help="run every network as training.model.MirrorAverage (export --mirror-average)",
    )
    p.add_argument("--seed", type=int, default=2021)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default="runs/eval")
    add_family_arguments(p)
    args = p.parse_args(argv)
    return args


def add_family_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``--families`` (:mod:`training.evaluate_families`)."""
    p.add_argument(
        "--families",
        nargs="?",
        const=",".join(FAMILIES),
        default=None,
        help=f"evaluate by light family (comma list of {', '.join(FAMILIES)}; default all)",
    )
    p.add_argument(
        "--model",
        action="append",
        default=[],
        metavar="NAME=DIR",
        help="--families: an installed model folder to evaluate (repeat for several)",
    )
    p.add_argument(
        "--with-camera",
        action="append",
        default=[],
        metavar="NAME",
        help="--families: also evaluate NAME (a --model name or 'geometric') with the true camera",
    )
    p.add_argument(
        "--with-gt-ao",
        action="append",
        default=[],
        metavar="NAME",
        help="--families: also evaluate model NAME with the ground-truth AO",
    )


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.families:
        results = evaluate_families(args)
        print(families_markdown(results))
        print(f"{results['seconds']:.0f} s; written to {args.out}")
        return 0
    results = evaluate(args)
    print(tables_markdown(results))
    print(f"{results['seconds']:.0f} s; written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
